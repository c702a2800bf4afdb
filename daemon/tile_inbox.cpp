#include "daemon/tile_inbox.h"

#include <utility>

namespace omega::daemon {

void TileInbox::push(TileUpdate t) {
  bool start = false, now = false;
  {
    std::lock_guard lock(mutex_);
    now = t.first;
    pending_.push_back(std::move(t));
    start = !due_;
    due_ = true;
  }
  if (start) loop_.post([this] { on_due(); });
  // A job's first tile does not wait for a batch another job's tiles started.
  else if (now) loop_.post([this] { drain(); });
}

void TileInbox::drain() {
  std::vector<TileUpdate> batch;
  {
    std::lock_guard lock(mutex_);
    batch = take_locked();
  }
  if (!batch.empty()) deliver_(std::move(batch));
}

void TileInbox::on_due() {
  std::vector<TileUpdate> batch;
  {
    std::lock_guard lock(mutex_);
    batch = take_locked();
    // Nothing came since the last batch: quiet again, the next tile goes at once.
    if (batch.empty()) {
      due_ = false;
      return;
    }
  }
  deliver_(std::move(batch));
  // Tiles are coming: look again in batch_s, whatever arrives meanwhile waits for that.
  loop_.add_timer(batch_s_, [this] { on_due(); });
}

}  // namespace omega::daemon
