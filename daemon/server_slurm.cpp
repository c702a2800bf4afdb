// executor: slurm (docs/farm.md "Workers under Slurm"). Loop thread; Slurm's commands run on the
// background thread (slurm_executor.h) and post their outcome back.
#include "daemon/server.h"

namespace omega::daemon {

using protocol::JobState;

bool Server::needs_work(std::uint64_t job) const {
  auto it = work_.find(job);
  if (it == work_.end() || it->second.finishing) return false;
  const WorkJob& w = it->second;
  for (const UnitRecord& u : w.units)
    if (u.state == UnitState::queued) return true;
  return (w.units.empty() ? 0 : w.units.back().end) < w.target;
}

void Server::poll_slurm() {
  if (cfg_.executor != "slurm" || slurm_polling_ || phase_ != Phase::serving) return;
  const auto now = std::chrono::steady_clock::now();
  if (now < next_slurm_poll_) return;
  next_slurm_poll_ = now + std::chrono::milliseconds(static_cast<long>(cfg_.slurm.poll_s * 1000));
  std::vector<std::string> ids;
  try {
    for (const auto& r : store_->active_slurm_jobs()) ids.push_back(r.slurm_id);
  } catch (const std::exception& e) {
    log_.error("slurm: cannot read the recorded Slurm jobs: {}", e.what());
    return;
  }
  slurm_polling_ = true;
  background_.submit([this, ids] {  // background thread
    std::map<std::string, int> alive;
    std::string err;
    try {
      alive = alive_tasks(ids);
    } catch (const std::exception& e) {
      err = e.what();
    }
    loop_.post([this, alive, err] {
      on_slurm_alive(alive, err);
      flush_dirty();
    });
  });
}

void Server::on_slurm_alive(const std::map<std::string, int>& alive, const std::string& error) {
  slurm_polling_ = false;
  if (!error.empty()) {
    log_.error("slurm: {}; trying again in {} s", error, cfg_.slurm.poll_s);
    return;
  }
  try {
    std::map<std::uint64_t, int> live;  // job -> tasks pending or running
    for (const auto& r : store_->active_slurm_jobs()) {
      auto a = alive.find(r.slurm_id);
      if (a == alive.end()) {
        store_->end_slurm_job(r.slurm_id);
        log_.info("job {}: Slurm job {} has ended (no task pending or running)", r.job, r.slurm_id);
      } else {
        live[r.job] += a->second;
      }
    }
    for (const auto& [job, w] : work_) {
      if (slurm_launching_.count(job) || !needs_work(job)) continue;
      std::optional<JobRecord> r = store_->get(job);
      if (!r || (r->state != JobState::queued && r->state != JobState::running)) continue;
      const int want = static_cast<int>(r->workers) - live[job];
      if (want <= 0) continue;
      const bool first = store_->count_slurm_jobs(job) == 0;
      int& started = slurm_started_[job];
      if (!first && started >= static_cast<int>(r->workers) + cfg_.slurm.max_replacements) {
        if (started < static_cast<int>(r->workers) + cfg_.slurm.max_replacements + 1) {
          log_.warn("job {}: Slurm workers keep ending ({} started); not starting more (slurm.max_replacements {})",
                    job, started, cfg_.slurm.max_replacements);
          started += 1;  // warn once
        }
        continue;
      }
      if (!first) log_.warn("job {}: {} of its Slurm workers ended with work left; starting {} more", job, want, want);
      start_slurm_workers(job, want);
    }
  } catch (const std::exception& e) {
    log_.error("slurm: cannot record the Slurm jobs' state: {}", e.what());
  }
}

void Server::start_slurm_workers(std::uint64_t job, int count) {
  slurm_launching_.insert(job);
  slurm_started_[job] += count;
  const SlurmSettings s = cfg_.slurm;
  const std::string dir = cfg_.state_dir + "/slurm";
  background_.submit([this, job, count, s, dir] {  // background thread
    std::string id, err;
    try {
      id = submit_workers(s, dir, job, count);
    } catch (const std::exception& e) {
      err = e.what();
    }
    loop_.post([this, job, count, id, err] {
      slurm_launching_.erase(job);
      if (!err.empty()) {
        log_.error("job {}: cannot start Slurm workers: {}; workers started by hand still serve it", job, err);
        return;
      }
      try {
        store_->add_slurm_job(job, id, count);
      } catch (const std::exception& e) {
        log_.error("job {}: cannot record Slurm job {}: {}; cancelling it", job, id, e.what());
        background_.submit([id] { cancel_workers({id}); });
        return;
      }
      log_.info("job {}: Slurm job {}: {} worker(s) submitted", job, id, count);
      if (!is_worker_job(job)) stop_slurm_workers(job, "the job ended meanwhile");
      flush_dirty();
    });
  });
}

void Server::stop_slurm_workers(std::uint64_t job, const std::string& why) {
  if (cfg_.executor != "slurm") return;
  std::vector<std::string> ids;
  try {
    for (const auto& r : store_->active_slurm_jobs())
      if (r.job == job) {
        ids.push_back(r.slurm_id);
        store_->end_slurm_job(r.slurm_id);
      }
  } catch (const std::exception& e) {
    log_.error("job {}: cannot read its Slurm jobs: {}", job, e.what());
  }
  if (ids.empty()) return;
  std::string list;
  for (const auto& id : ids) list += (list.empty() ? "" : " ") + id;
  log_.info("job {}: scancel {} ({})", job, list, why);
  background_.submit([this, job, ids] {  // background thread
    const std::string err = cancel_workers(ids);
    if (!err.empty()) loop_.post([this, job, err] { log_.error("job {}: {}", job, err); });
  });
}

}  // namespace omega::daemon
