#pragma once
// One thread for blocking work the loop must not do itself: scene validation, whole-image EXR
// encoding for fetch, tiles for late subscribers. Tasks run in order; each posts its result back
// to the loop.
#include <condition_variable>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>

namespace omega::daemon {

class Background {
 public:
  Background();
  ~Background();  // finishes queued tasks, then joins
  // Any thread; takes mutex_.
  void submit(std::function<void()> task);

 private:
  void run();
  std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<std::function<void()>> tasks_;  // guarded by mutex_
  bool stopping_ = false;                    // guarded by mutex_
  std::thread thread_;
};

}  // namespace omega::daemon
