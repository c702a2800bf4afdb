#include "daemon/scheduler.h"

#include <algorithm>

namespace omega::daemon {

SchedDecision schedule(const std::vector<SchedJob>& queued, std::vector<SchedJob> running, int slots, int stopping) {
  SchedDecision d;
  int free = slots - static_cast<int>(running.size());
  std::size_t qi = 0;
  for (; qi < queued.size() && free > 0; ++qi, --free) d.start.push_back(queued[qi].id);
  // Lowest priority first; among equals the newest (largest id) is preempted first.
  std::sort(running.begin(), running.end(), [](const SchedJob& a, const SchedJob& b) {
    return a.priority != b.priority ? a.priority < b.priority : a.id > b.id;
  });
  std::size_t ri = 0;
  // A job already being preempted (stopping) will free a slot for the best queued job.
  qi += static_cast<std::size_t>(std::max(0, std::min<int>(stopping, int(queued.size()) - int(qi))));
  for (; qi < queued.size() && ri < running.size(); ++qi, ++ri) {
    if (queued[qi].priority <= running[ri].priority) break;
    d.preempt.push_back(running[ri].id);
  }
  return d;
}

}  // namespace omega::daemon
