#pragma once
// Progressive delivery: per job, the newest encoded version of every tile and the newest
// progress, and the subscriptions watching it. A new subscriber first gets every tile's current
// state; then each pass's tiles go to every subscriber through its coalescing output queue, so a
// slow one never holds anybody up. Loop thread only.
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "daemon/output_queue.h"
#include "daemon/render_worker.h"
#include "protocol/messages.h"

namespace omega::daemon {

// Where frames go (the Server): by connection id; unknown ids are ignored.
class FrameSink {
 public:
  virtual ~FrameSink() = default;
  virtual void send_frame(std::uint64_t conn, const protocol::Frame& f) = 0;
  virtual void send_coalesced(std::uint64_t conn, const CoalesceKey& key, const std::string& header,
                              std::shared_ptr<const std::string> payload) = 0;
};

class TilePublisher {
 public:
  explicit TilePublisher(FrameSink& sink) : sink_(sink) {}

  // Sends the current tiles and progress; for a finished job also done (which ends it).
  void subscribe(std::uint64_t job, std::uint64_t conn, std::uint64_t sub_id);
  bool unsubscribe(std::uint64_t job, std::uint64_t conn, std::uint64_t sub_id);
  void drop_connection(std::uint64_t conn);

  // New tiles of a whole pass (version = their spp, so versions only grow). A tile older than
  // the one held is ignored.
  void update_tiles(std::uint64_t job, const std::vector<EncodedTile>& tiles, std::uint64_t pass, std::uint64_t spp);
  // One tile finished in the middle of a pass (path tracing), sent at once.
  void update_tile(std::uint64_t job, const EncodedTile& tile, std::uint64_t pass, std::uint64_t spp);
  // Every tile held has reached spp (they streamed one by one during the pass).
  void tiles_complete(std::uint64_t job, std::uint64_t spp);
  void progress(std::uint64_t job, protocol::JobState state, const protocol::ProgressInfo& p);
  // Sends done to every subscriber and ends their subscriptions. Later subscribers get the
  // tiles and done at once.
  void done(std::uint64_t job, protocol::JobState state, const protocol::ProgressInfo& p,
            std::optional<std::string> message);
  void forget(std::uint64_t job);  // the job was deleted

  std::size_t watchers(std::uint64_t job) const;
  std::uint64_t tiles_spp(std::uint64_t job) const;  // 0 when no tiles are held
  bool has_tiles(std::uint64_t job) const;

 private:
  struct TileState {
    protocol::Rect rect;
    std::uint64_t pass = 0, spp = 0, version = 0;
    std::shared_ptr<const std::string> exr;
  };
  struct Sub {
    std::uint64_t conn = 0, id = 0;
  };
  struct JobEntry {
    std::map<std::uint64_t, TileState> tiles;  // by slot (x0 << 32 | y0), row-major order
    std::uint64_t tiles_spp = 0;  // every tile held has at least this many samples
    std::vector<Sub> subs;
    std::optional<protocol::Progress> progress;  // id 0; stamped per subscriber
    std::optional<protocol::Done> done;
  };
  void send_tile(const Sub& s, std::uint64_t job, const TileState& t);
  void send_progress(const Sub& s, const protocol::Progress& p);
  void store_tile(std::uint64_t job, JobEntry& e, const EncodedTile& et, std::uint64_t pass, std::uint64_t spp);

  FrameSink& sink_;
  std::map<std::uint64_t, JobEntry> jobs_;
};

}  // namespace omega::daemon
