#pragma once
// A connection's bounded output queue. Replies are queued as they come and count against a byte
// limit. Tile and progress frames are coalesced by key (subscription, job, rect): a newer one
// replaces a queued older one in place, so a slow reader holds at most one frame per rect and the
// renderer never waits for it. Payloads are shared between subscribers (one EXR per tile version).
// Loop thread only.
#include <sys/uio.h>

#include <cstdint>
#include <list>
#include <map>
#include <memory>
#include <string>
#include <tuple>

namespace omega::daemon {

struct CoalesceKey {
  std::uint64_t subscription = 0;  // the subscribe's id
  std::uint64_t job = 0;
  std::uint64_t slot = 0;  // a tile's (x0 << 32 | y0); kProgressSlot for progress frames
  auto operator<=>(const CoalesceKey&) const = default;
};
inline constexpr std::uint64_t kProgressSlot = ~std::uint64_t(0);

class OutputQueue {
 public:
  // A whole frame that is never dropped. Counts against the limit.
  void push(std::string bytes);
  // prelude + header in `head`, the payload shared. Replaces a queued frame with the same key
  // unless that one is already partly written (then it is appended).
  void push_coalesced(const CoalesceKey& key, std::string head, std::shared_ptr<const std::string> payload);

  bool empty() const { return items_.empty(); }
  std::size_t frames() const { return items_.size(); }
  // Bytes of non-coalesced frames waiting (what the per-client limit applies to).
  std::size_t owned_bytes() const { return owned_bytes_; }
  std::size_t coalesced_replacements() const { return replaced_; }

  // Fills up to max iovecs with the bytes at the front; returns how many.
  int fill_iov(iovec* iov, int max) const;
  // Drops n written bytes from the front.
  void consume(std::size_t n);

 private:
  struct Item {
    std::string head;
    std::shared_ptr<const std::string> payload;  // null for plain frames
    std::size_t offset = 0;                      // bytes of head+payload already written
    bool keyed = false;
    CoalesceKey key;
    std::size_t size() const { return head.size() + (payload ? payload->size() : 0); }
  };
  std::list<Item> items_;
  std::map<CoalesceKey, std::list<Item>::iterator> index_;
  std::size_t owned_bytes_ = 0;
  std::size_t replaced_ = 0;
};

}  // namespace omega::daemon
