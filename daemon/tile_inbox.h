#pragma once
// Tiles the render threads finish, on their way to the loop, which sends them to the watchers.
//
// One post per tile woke the loop once per tile, and on a machine whose cores all render, each
// wake-up takes a core from a render thread (a watched 256x256 job of 448 tiles: 544 posts and
// 532 epoll_wait returns; batched, 35 and 117; docs/daemon.md has the CPU figures). So tiles go
// in batches: the first tile after a quiet spell, and a job's first streamed tile (TileUpdate::
// first), at once (a preview's first tile waits for nothing); later ones together, one batch per
// `batch_s` (a timer on the loop, while tiles keep coming). A tile is at most batch_s late.
//
// Concurrency: push() is called by the render threads (several at once) and takes mutex_;
// drain() and the delivery run on the loop thread. The loop must outlive nothing here: a timer
// or post left when the loop stops is dropped with it, unrun.
#include <functional>
#include <mutex>
#include <utility>
#include <vector>

#include "daemon/event_loop.h"
#include "daemon/render_worker.h"

namespace omega::daemon {

class TileInbox {
 public:
  using Deliver = std::function<void(std::vector<TileUpdate>)>;  // loop thread
  TileInbox(EventLoop& loop, double batch_s, Deliver deliver)
      : loop_(loop), batch_s_(batch_s), deliver_(std::move(deliver)) {}
  TileInbox(const TileInbox&) = delete;
  TileInbox& operator=(const TileInbox&) = delete;

  // Render threads: queues a finished tile; wakes the loop only when no batch is due.
  void push(TileUpdate t);
  // Loop thread: delivers what waits now. A pass boundary and a job's end call it first: the
  // render threads queued every tile of that pass before posting the boundary, so the
  // watchers still get the tiles before the progress that follows them.
  void drain();

 private:
  void on_due();  // loop thread: a batch is due (the first tile's post, or the timer)
  std::vector<TileUpdate> take_locked() { return std::exchange(pending_, {}); }  // holds mutex_

  EventLoop& loop_;
  const double batch_s_;
  Deliver deliver_;
  std::mutex mutex_;
  std::vector<TileUpdate> pending_;  // guarded by mutex_
  bool due_ = false;                 // guarded by mutex_: a post or a timer will run on_due()
};

}  // namespace omega::daemon
