#include "daemon/scheduler.h"

#include <gtest/gtest.h>

namespace omega::daemon {
namespace {

using V = std::vector<std::uint64_t>;

TEST(Scheduler, StartsByPriorityThenFifoUpToTheSlots) {
  auto d = schedule({{5, 9}, {2, 0}, {3, 0}}, {}, 2);
  EXPECT_EQ(d.start, (V{5, 2}));
  EXPECT_TRUE(d.preempt.empty());
}

TEST(Scheduler, PreemptsTheLowestPriorityRunningJobOnlyForAStrictlyHigherOne) {
  auto d = schedule({{9, 5}}, {{1, 0}, {2, 3}}, 2);
  EXPECT_TRUE(d.start.empty());
  EXPECT_EQ(d.preempt, (V{1}));
  EXPECT_TRUE(schedule({{9, 0}}, {{1, 0}}, 1).preempt.empty());  // equal priority waits
}

TEST(Scheduler, APreemptionUnderWayIsNotRepeated) {
  // Job 1 is already stopping for job 9: nothing more to do until it has.
  auto d = schedule({{9, 5}}, {{2, 3}}, 1, 1);
  EXPECT_TRUE(d.start.empty());
  EXPECT_TRUE(d.preempt.empty());
}

}  // namespace
}  // namespace omega::daemon
