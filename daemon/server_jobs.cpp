// Job lifecycle: validation of submits, scheduling, and events from render workers. Loop thread
// unless noted.
#include <filesystem>
#include <fstream>

#include "daemon/scene_limits.h"
#include "daemon/scheduler.h"
#include "daemon/server.h"
#include "integrator/render_session.h"
#include "scene/scene.h"
#include "scene/scene_error.h"

namespace omega::daemon {

namespace fs = std::filesystem;
using protocol::ErrorCode;
using protocol::JobState;

void Server::validate(Connection& c, std::uint64_t submit_id) {
  PendingSubmit& p = c.pending.at(submit_id);
  p.validating = true;
  protocol::Submit s = p.submit;
  std::string staging = cfg_.state_dir + "/staging/" + std::to_string(::getpid()) + "-" + std::to_string(next_staging_++);
  std::vector<std::string> roots = cfg_.allowed_roots;
  std::uint64_t conn = c.id();
  const SceneLimits limits{cfg_.max_resolution, cfg_.max_spp, cfg_.max_time_s, cfg_.max_scene_memory_bytes};
  // Background thread: parse, resolve assets and build the scene, so a bad one is refused now.
  background_.submit([this, conn, s = std::move(s), staging, roots, limits] {
    Validation v;
    v.staging = staging;
    try {
      JobPaths jp{staging};
      fs::create_directories(jp.files());
      write_file_atomic(jp.scene(), s.scene);
      for (const auto& a : s.assets) assets_->materialize(a.sha256, a.size, jp.files() + "/" + a.name);
      SceneDesc desc = load_job_scene(jp, s.name, s.integrator.value_or(""), roots);
      std::uint64_t asset_bytes = 0;
      for (const auto& a : s.assets) asset_bytes += a.size;
      check_scene_limits(limits, desc, asset_bytes, scene_file_name(s.name));  // before the costly build
      std::unique_ptr<Scene> scene = Scene::build(desc);
      check_built_scene_memory(limits, desc, *scene, scene_file_name(s.name));
      RenderSettings rs;
      rs.threads = 1;
      rs.integrator = desc.integrator;
      RenderSession check(*scene, rs);  // refuses integrators this build lacks
      v.halt = s.halt;
      if (!v.halt.spp && !v.halt.time_s && !v.halt.target_error) {
        const HaltDesc& h = desc.sensor.halt;
        if (h.spp) v.halt.spp = static_cast<std::uint64_t>(*h.spp);
        v.halt.time_s = h.time_s;
        v.halt.target_error = h.target_error;
        if (!h.spp && !h.time_s && !h.target_error) v.halt.spp = 64;
      }
      if (!v.halt.spp && !v.halt.time_s) v.halt.time_s = limits.max_time_s;  // target_error alone: bounded in time
      check_halt_limits(limits, v.halt, scene_file_name(s.name));
      v.ok = true;
    } catch (const SceneError& e) {
      v.message = e.what();
    } catch (const std::invalid_argument& e) {
      v.message = scene_file_name(s.name) + ":1: integrator: " + e.what();
    } catch (const std::exception& e) {
      v.code = std::string(e.what()).find("corrupt") != std::string::npos ? ErrorCode::asset_mismatch : ErrorCode::internal;
      v.message = e.what();
    }
    if (!v.ok) {
      std::error_code ec;
      fs::remove_all(staging, ec);
    }
    loop_.post([this, conn, s, v = std::move(v)]() mutable {
      on_validated(conn, s, std::move(v));
      flush_dirty();
    });
  });
}

void Server::on_validated(std::uint64_t conn, const protocol::Submit& s, Validation v) {
  Connection* c = find(conn);
  std::error_code ec;
  if (c) c->pending.erase(s.id);
  if (v.ok && (!c || phase_ != Phase::serving)) {
    fs::remove_all(v.staging, ec);
    if (c) reply_error(*c, s.id, ErrorCode::shutting_down, "omegad is shutting down");
    else log_.info("submit '{}' dropped: the client left before it was accepted", s.name);
    return;
  }
  if (!v.ok) {
    log_.warn("submit '{}' from {} refused ({}): {}", s.name, c ? c->peer().name : "a departed client",
              protocol::to_string(v.code), v.message);
    if (c) reply_error(*c, s.id, v.code, v.message);
    return;
  }
  JobRecord r;
  r.name = s.name;
  r.owner = c->user;
  r.priority = s.priority;
  r.state = JobState::queued;
  r.halt = v.halt;
  r.seed = s.seed;
  r.integrator = s.integrator.value_or("");
  std::uint64_t job = 0;
  try {
    job = store_->insert(r, [&](std::uint64_t id) {
      std::string dir = paths(id).dir;
      fs::remove_all(dir, ec);  // an orphan from a crash between rename and commit
      fs::rename(v.staging, dir);
    });
  } catch (const std::exception& e) {
    fs::remove_all(v.staging, ec);
    log_.error("submit '{}': cannot store the job: {}", s.name, e.what());
    const std::string what = e.what();
    const bool transient = what.find("locked") != std::string::npos || what.find("busy") != std::string::npos ||
                           what.find("disk") != std::string::npos || what.find("No space") != std::string::npos;
    return reply_error(*c, s.id, transient ? ErrorCode::busy : ErrorCode::internal,
                       "cannot store the job: " + what);
  }
  log_.info("job {} accepted from {} (user {}): '{}', priority {}, seed {}", job, c->peer().name, c->user, s.name,
            s.priority, s.seed);
  protocol::Accepted a;
  a.id = s.id;
  a.job = job;
  c->send(protocol::encode(a));
  dirty_.insert(conn);
  reschedule();
}

void Server::reschedule() {
  if (phase_ != Phase::serving) return;
  std::vector<SchedJob> queued, running;
  int stopping = 0, preempting = 0;
  for (auto& [id, a] : active_) {
    StopKind k = a.worker->stop_requested();
    if (k == StopKind::none) {
      std::optional<JobRecord> r = store_->get(id);
      running.push_back(SchedJob{id, r ? r->priority : 0});
    } else {
      ++stopping;
      if (k == StopKind::preempt) ++preempting;
    }
  }
  std::vector<JobRecord> q = store_->queued();
  std::map<std::uint64_t, JobRecord> by_id;
  for (const JobRecord& r : q) {
    if (active_.count(r.id)) continue;  // its previous worker is still stopping
    queued.push_back(SchedJob{r.id, r.priority});
    by_id.emplace(r.id, r);
  }
  SchedDecision d = schedule(queued, running, cfg_.max_running - stopping, preempting);
  for (std::uint64_t id : d.preempt) {
    log_.info("job {}: preempted by a higher-priority job; back to the queue", id);
    active_.at(id).worker->request_stop(StopKind::preempt);
    store_->set_state(id, JobState::queued);
  }
  for (std::uint64_t id : d.start) start_job(by_id.at(id));
}

void Server::start_job(const JobRecord& r) {
  WorkerSpec spec;
  spec.job = r.id;
  spec.paths = paths(r.id);
  spec.name = r.name;
  spec.integrator = r.integrator;
  spec.halt = r.halt;
  spec.seed = r.seed;
  spec.threads = cfg_.threads;
  spec.tile_size = cfg_.tile_size;
  spec.checkpoint_interval_s = cfg_.checkpoint_interval_s;
  spec.allowed_roots = cfg_.allowed_roots;
  spec.resume = memo_[r.id].snapshot;
  // Both callbacks run on the worker's driver thread and only post to the loop.
  auto worker = std::make_unique<RenderWorker>(
      std::move(spec), log_,
      [this](PassUpdate u) {
        loop_.post([this, u = std::move(u)]() mutable {
          on_pass(std::move(u));
          flush_dirty();
        });
      },
      [this](WorkerResult res) {
        loop_.post([this, res = std::move(res)]() mutable {
          on_finish(std::move(res));
          flush_dirty();
        });
      });
  worker->set_watched(publisher_.watchers(r.id) > 0);
  store_->set_state(r.id, JobState::running);
  publisher_.progress(r.id, JobState::running, r.progress);
  log_.info("job {}: started ('{}', priority {})", r.id, r.name, r.priority);
  worker->start();
  active_[r.id].worker = std::move(worker);
}

void Server::on_pass(PassUpdate u) {
  Memo& m = memo_[u.job];
  m.snapshot = u.snapshot;
  m.film = u.film;
  std::optional<JobRecord> r = store_->get(u.job);
  if (!r) return;
  store_->set_progress(u.job, u.progress);
  if (!u.tiles.empty()) publisher_.update_tiles(u.job, u.tiles, u.progress.pass, u.progress.spp);
  publisher_.progress(u.job, r->state, u.progress);
  log_.debug("job {}: pass {} done, {} spp, {:.2f} s", u.job, u.progress.pass, u.progress.spp, u.progress.elapsed_s);
}

void Server::on_finish(WorkerResult res) {
  auto it = active_.find(res.job);
  if (it != active_.end()) {
    it->second.worker->join();
    active_.erase(it);
  }
  if (res.last) memo_[res.job].snapshot = res.last;
  std::optional<JobRecord> r = store_->get(res.job);
  if (r) {
    protocol::ProgressInfo p = r->progress;
    if (res.last) {
      p.pass = res.last->pass;
      p.spp = res.last->spp;
      p.elapsed_s = res.last->elapsed_s;
      p.rel_error = res.last->rel_error;
    }
    switch (res.outcome) {
      case WorkerResult::Outcome::done:
        if (r->state == JobState::running) {
          store_->set_progress(res.job, p);
          store_->set_state(res.job, JobState::done);
          publisher_.done(res.job, JobState::done, p, std::nullopt);
          log_.info("job {}: done: {} spp in {:.2f} s", res.job, p.spp, p.elapsed_s);
        }
        memo_.erase(res.job);  // result.exr and the final checkpoint serve it from now on
        break;
      case WorkerResult::Outcome::failed:
        store_->set_state(res.job, JobState::failed, res.message);
        publisher_.done(res.job, JobState::failed, p, res.message);
        log_.error("job {}: failed: {}", res.job, res.message);
        break;
      case WorkerResult::Outcome::stopped:
        log_.info("job {}: stopped ({}) at {} spp", res.job, to_string(res.stop), p.spp);
        if (res.stop == StopKind::pause || res.stop == StopKind::preempt) publisher_.progress(res.job, store_->get(res.job)->state, p);
        break;
    }
  }
  reschedule();
  maybe_finish_shutdown();
}

void Server::update_watched(std::uint64_t job) {
  auto it = active_.find(job);
  if (it != active_.end()) it->second.worker->set_watched(publisher_.watchers(job) > 0);
}

std::shared_ptr<const FilmSnapshot> Server::latest_snapshot(std::uint64_t job) {
  Memo& m = memo_[job];
  if (m.snapshot) return m.snapshot;
  try {
    if (auto ck = read_checkpoint(paths(job).checkpoint())) m.snapshot = std::make_shared<const FilmSnapshot>(std::move(*ck));
  } catch (const std::exception& e) {
    log_.error("job {}: {}", job, e.what());
  }
  return m.snapshot;
}

}  // namespace omega::daemon
