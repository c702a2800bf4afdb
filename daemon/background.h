#pragma once
// One thread for blocking work the loop must not do itself: scene validation, whole-image EXR
// encoding for fetch, tiles for late subscribers. Tasks run in order; each posts its result back
// to the loop. At destruction (omegad is exiting) tasks not yet started are dropped, and the
// running one can see stopping() and give up early (a scene build polls it).
#include <atomic>
#include <condition_variable>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>

namespace omega::daemon {

class Background {
 public:
  Background();
  ~Background();  // drops queued tasks, waits for the running one, joins
  // Any thread; takes mutex_.
  void submit(std::function<void()> task);
  // Any thread: true once destruction has begun.
  bool stopping() const { return stopping_flag_.load(); }

 private:
  void run();
  std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<std::function<void()>> tasks_;  // guarded by mutex_
  bool stopping_ = false;                    // guarded by mutex_
  std::atomic<bool> stopping_flag_{false};   // the same, readable without the lock
  std::thread thread_;
};

}  // namespace omega::daemon
