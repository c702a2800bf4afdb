#include "daemon/output_queue.h"

namespace omega::daemon {

void OutputQueue::push(std::string bytes) {
  owned_bytes_ += bytes.size();
  items_.push_back(Item{std::move(bytes), nullptr, 0, false, {}});
}

void OutputQueue::push_coalesced(const CoalesceKey& key, std::string head,
                                 std::shared_ptr<const std::string> payload) {
  auto it = index_.find(key);
  if (it != index_.end() && it->second->offset == 0) {
    it->second->head = std::move(head);
    it->second->payload = std::move(payload);
    ++replaced_;
    return;
  }
  items_.push_back(Item{std::move(head), std::move(payload), 0, true, key});
  index_[key] = std::prev(items_.end());
}

int OutputQueue::fill_iov(iovec* iov, int max) const {
  int n = 0;
  for (auto it = items_.begin(); it != items_.end() && n + 2 <= max; ++it) {
    std::size_t off = it->offset;
    if (off < it->head.size()) {
      iov[n].iov_base = const_cast<char*>(it->head.data() + off);
      iov[n].iov_len = it->head.size() - off;
      ++n;
      off = 0;
    } else {
      off -= it->head.size();
    }
    if (it->payload && off < it->payload->size()) {
      iov[n].iov_base = const_cast<char*>(it->payload->data() + off);
      iov[n].iov_len = it->payload->size() - off;
      ++n;
    }
  }
  return n;
}

void OutputQueue::consume(std::size_t n) {
  while (n > 0 && !items_.empty()) {
    Item& front = items_.front();
    std::size_t left = front.size() - front.offset;
    if (n < left) {
      front.offset += n;
      return;
    }
    n -= left;
    if (front.keyed) {
      auto it = index_.find(front.key);
      if (it != index_.end() && it->second == items_.begin()) index_.erase(it);
    } else {
      owned_bytes_ -= front.head.size();
    }
    items_.pop_front();
  }
}

}  // namespace omega::daemon
