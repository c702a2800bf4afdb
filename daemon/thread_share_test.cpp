// The render threads' share per job: proportional to weight, never more tiles at once than
// slots, and work-conserving. Work is a sleep, so the shares hold on a loaded machine.
#include "daemon/thread_share.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>
#include <vector>

namespace omega::daemon {
namespace {

using namespace std::chrono_literals;

struct Probe {
  std::atomic<int> running{0}, most{0};
  std::function<void()> work(std::chrono::milliseconds d) {
    return [this, d] {
      int now = running.fetch_add(1) + 1;
      int m = most.load();
      while (now > m && !most.compare_exchange_weak(m, now)) {
      }
      std::this_thread::sleep_for(d);
      running.fetch_sub(1);
    };
  }
};

// Threads per job, each running tiles until the clock says stop. Like the daemon, each job has
// twice as many threads as slots, so one is waiting whenever another finishes a tile.
void contend(ThreadShare& share, const std::vector<std::uint64_t>& jobs, int threads_per_job,
             std::chrono::milliseconds for_how_long, Probe& probe) {
  std::atomic<bool> stop{false};
  std::vector<std::thread> threads;
  for (auto job : jobs)
    for (int t = 0; t < threads_per_job; ++t)
      threads.emplace_back([&, job] {
        auto w = probe.work(3ms);
        while (!stop.load()) share.run(job, w);
      });
  std::this_thread::sleep_for(for_how_long);
  stop.store(true);
  for (auto& t : threads) t.join();
}

TEST(ThreadShare, WeightsFromPriority) {
  EXPECT_DOUBLE_EQ(share_weight(0), 1.0);
  EXPECT_DOUBLE_EQ(share_weight(10), 2.0);
  EXPECT_DOUBLE_EQ(share_weight(-10), 0.5);
  EXPECT_DOUBLE_EQ(share_weight(30), 8.0);
  EXPECT_DOUBLE_EQ(share_weight(1'000'000), share_weight(600));  // clamped, finite
  EXPECT_GT(share_weight(-1'000'000), 0.0);
}

// Thread time that job a gets over job b's while both contend for `how_long`, from now on.
double contended_ratio(ThreadShare& share, std::uint64_t a, std::uint64_t b, std::chrono::milliseconds how_long,
                       Probe& probe) {
  const double a0 = share.used_s(a), b0 = share.used_s(b);
  contend(share, {a, b}, 4, how_long, probe);
  return (share.used_s(a) - a0) / (share.used_s(b) - b0);
}

TEST(ThreadShare, SharesFollowTheWeights) {
  ThreadShare share(2);
  share.add(1, share_weight(10));
  share.add(2, share_weight(0));
  Probe probe;
  const double ratio = contended_ratio(share, 1, 2, 900ms, probe);
  EXPECT_LE(probe.most.load(), 2);
  EXPECT_GT(ratio, 1.6);
  EXPECT_LT(ratio, 2.5);
}

TEST(ThreadShare, EqualWeightsShareEvenly) {
  ThreadShare share(2);
  share.add(1, 1.0);
  share.add(2, 1.0);
  Probe probe;
  const double ratio = contended_ratio(share, 1, 2, 600ms, probe);
  EXPECT_GT(ratio, 0.8);
  EXPECT_LT(ratio, 1.25);
}

TEST(ThreadShare, AJobAloneGetsEverySlotWhateverItsWeight) {
  ThreadShare share(3);
  share.add(7, share_weight(-100));
  Probe probe;
  contend(share, {7}, 6, 200ms, probe);
  EXPECT_EQ(probe.most.load(), 3);
}

TEST(ThreadShare, ANewcomerDoesNotMakeUpForTimeBeforeItRan) {
  ThreadShare share(2);
  share.add(1, 1.0);
  Probe probe;
  contend(share, {1}, 4, 300ms, probe);
  share.add(2, 1.0);
  const double ratio = contended_ratio(share, 1, 2, 600ms, probe);
  EXPECT_GT(ratio, 0.8);  // without the clock start, job 1 would get nothing for 300 ms
  EXPECT_LT(ratio, 1.25);
}

TEST(ThreadShare, AWeightChangeTakesEffect) {
  ThreadShare share(2);
  share.add(1, 1.0);
  share.add(2, 1.0);
  Probe probe;
  contend(share, {1, 2}, 4, 300ms, probe);
  share.set_weight(2, share_weight(20));
  const double ratio = contended_ratio(share, 2, 1, 900ms, probe);
  EXPECT_GT(ratio, 3.0);
  EXPECT_LT(ratio, 5.5);
}

TEST(ThreadShare, UnknownJobsRunAtOnce) {
  ThreadShare share(1);
  bool ran = false;
  share.run(42, [&] { ran = true; });
  EXPECT_TRUE(ran);
  EXPECT_EQ(share.used_s(42), 0.0);
}

}  // namespace
}  // namespace omega::daemon
