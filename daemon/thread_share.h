#pragma once
// How running jobs share the render threads: in proportion to a weight derived from priority.
//
// Each job's render session runs on twice as many threads as the daemon has, but at most `slots`
// tiles run at once, daemon-wide. When a slot frees, it goes to the waiting job that has used
// the least thread time per unit of weight (stride scheduling, Waldspurger and Weihl 1995), so
// over a few tiles each job's share of thread time is its weight over the sum of the running
// jobs' weights. The policy is work-conserving: a job alone gets every slot, whatever its weight.
//
// Concurrency: add/remove/set_weight/set_slots run on the loop thread; run() on render threads.
// All take mutex_.
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <mutex>

namespace omega::daemon {

// Ten priority points double a job's share: weight = 2^(priority / 10), so priorities 10 and 0
// share 2:1, and 30 against 0 gets 8/9 of the threads.
double share_weight(std::int64_t priority);

class ThreadShare {
 public:
  explicit ThreadShare(int slots) : slots_(slots > 0 ? slots : 1) {}

  void set_slots(int slots);
  // A job starts sharing. Its clock starts at the least used among the others, so a newcomer
  // neither makes up for the time before it ran nor is made to wait for it.
  void add(std::uint64_t job, double weight);
  void set_weight(std::uint64_t job, double weight);
  void remove(std::uint64_t job);  // no render thread of the job may be in run()

  // Render threads: waits for a slot that is this job's turn, runs work, and charges its time.
  // An unknown job (not added) runs at once, uncharged.
  void run(std::uint64_t job, const std::function<void()>& work);

  // Thread time charged to a job so far, in seconds (tests and logs).
  double used_s(std::uint64_t job) const;

 private:
  struct Entry {
    double weight = 1;
    double vtime = 0;    // thread seconds used / weight
    double used_s = 0;   // thread seconds used
    int waiting = 0;     // threads waiting for a slot
  };
  bool my_turn(std::uint64_t job) const;  // holds mutex_

  mutable std::mutex mutex_;
  std::condition_variable cv_;
  int slots_;
  int active_ = 0;
  std::map<std::uint64_t, Entry> jobs_;
};

}  // namespace omega::daemon
