#include "daemon/thread_share.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

namespace omega::daemon {

double share_weight(std::int64_t priority) {
  // Clamped so that no weight over- or underflows against another: 2^±60 is still exact.
  const double p = std::clamp(static_cast<double>(priority), -600.0, 600.0);
  return std::exp2(p / 10.0);
}

void ThreadShare::set_slots(int slots) {
  std::lock_guard lock(mutex_);
  slots_ = slots > 0 ? slots : 1;
  cv_.notify_all();
}

void ThreadShare::add(std::uint64_t job, double weight) {
  std::lock_guard lock(mutex_);
  double start = std::numeric_limits<double>::infinity();
  for (const auto& [id, e] : jobs_) start = std::min(start, e.vtime);
  Entry& e = jobs_[job];
  e.weight = weight > 0 ? weight : 1;
  e.vtime = std::isfinite(start) ? start : 0;
}

void ThreadShare::set_weight(std::uint64_t job, double weight) {
  std::lock_guard lock(mutex_);
  auto it = jobs_.find(job);
  if (it == jobs_.end() || !(weight > 0)) return;
  it->second.weight = weight;
  cv_.notify_all();
}

void ThreadShare::remove(std::uint64_t job) {
  std::lock_guard lock(mutex_);
  jobs_.erase(job);
  cv_.notify_all();
}

bool ThreadShare::my_turn(std::uint64_t job) const {
  if (active_ >= slots_) return false;
  auto it = jobs_.find(job);
  if (it == jobs_.end()) return true;
  const Entry& mine = it->second;
  for (const auto& [id, e] : jobs_)
    if (id != job && e.waiting > 0 && (e.vtime < mine.vtime || (e.vtime == mine.vtime && id < job))) return false;
  return true;
}

void ThreadShare::run(std::uint64_t job, const std::function<void()>& work) {
  {
    std::unique_lock lock(mutex_);
    auto it = jobs_.find(job);
    if (it == jobs_.end()) {
      lock.unlock();
      work();
      return;
    }
    it->second.waiting += 1;
    cv_.wait(lock, [&] { return my_turn(job); });
    if (auto again = jobs_.find(job); again != jobs_.end()) again->second.waiting -= 1;
    active_ += 1;
  }
  const auto t0 = std::chrono::steady_clock::now();
  struct Release {  // the slot is given back even if work throws
    ThreadShare& s;
    std::uint64_t job;
    std::chrono::steady_clock::time_point t0;
    ~Release() {
      const double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      std::lock_guard lock(s.mutex_);
      s.active_ -= 1;
      auto it = s.jobs_.find(job);
      if (it != s.jobs_.end()) {
        it->second.used_s += dt;
        it->second.vtime += dt / it->second.weight;
      }
      s.cv_.notify_all();
    }
  } release{*this, job, t0};
  work();
}

double ThreadShare::used_s(std::uint64_t job) const {
  std::lock_guard lock(mutex_);
  auto it = jobs_.find(job);
  return it == jobs_.end() ? 0 : it->second.used_s;
}

}  // namespace omega::daemon
