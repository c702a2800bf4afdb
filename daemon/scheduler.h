#pragma once
// Which jobs run. Pure policy, no I/O; the Server applies its decisions on the loop thread.
//
// Policy (docs/daemon.md, "Scheduling"): queued jobs start in order of priority (higher first),
// then submission (FIFO), while fewer than max_running jobs run. When every slot is taken and a
// queued job has a strictly higher priority than the lowest-priority running job, that running
// job is preempted: it stops at the next tile boundary, goes back to the queue and later resumes
// from its last pass boundary. Running jobs share the --threads workers by priority weight
// (thread_share.h).
#include <cstdint>
#include <vector>

namespace omega::daemon {

struct SchedJob {
  std::uint64_t id = 0;
  std::int64_t priority = 0;
};

struct SchedDecision {
  std::vector<std::uint64_t> start;    // queued jobs to start now
  std::vector<std::uint64_t> preempt;  // running jobs to send back to the queue
};

// queued: in run order (priority desc, id asc), excluding jobs whose previous worker is still
// stopping. running: jobs with a live worker not already stopping. slots: max_running less the
// workers still stopping. stopping: how many of those are preemptions already under way (each
// will free a slot for one of the best queued jobs, which therefore need no further preemption).
SchedDecision schedule(const std::vector<SchedJob>& queued, std::vector<SchedJob> running, int slots,
                       int stopping = 0);

}  // namespace omega::daemon
