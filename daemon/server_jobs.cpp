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

ErrorCode store_error_code(const std::string& what) {
  const bool transient = what.find("locked") != std::string::npos || what.find("busy") != std::string::npos ||
                         what.find("disk") != std::string::npos || what.find("No space") != std::string::npos;
  return transient ? ErrorCode::busy : ErrorCode::internal;
}

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
      write_file_atomic(jp.dir + "/assets.txt", format_asset_list(s.assets));  // for workers (unit_fold.h)
      SceneDesc desc = load_job_scene(jp, s.name, s.integrator.value_or(""), s.sampler.value_or(""), roots);
      std::uint64_t asset_bytes = 0;
      for (const auto& a : s.assets) asset_bytes += a.size;
      check_scene_limits(limits, desc, asset_bytes, scene_file_name(s.name));  // before the costly build
      std::unique_ptr<Scene> scene = Scene::build(desc, [this] { return background_.stopping(); });
      check_built_scene_memory(limits, desc, *scene, scene_file_name(s.name));
      RenderSettings rs;
      rs.integrator = desc.integrator;
      // Refuses what a session would, without its film: 64 MB and 50 ms for a 1024² submit.
      RenderSession::check_settings(rs);
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
    } catch (const BuildCancelled&) {
      v.code = ErrorCode::shutting_down;
      v.message = "omegad is shutting down";
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
  r.sampler = s.sampler.value_or("");
  r.workers = s.workers.value_or(static_cast<std::uint32_t>(cfg_.workers));
  r.unit_spp = s.unit_spp.value_or(0);
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
    return reply_error(*c, s.id, store_error_code(e.what()), std::string("cannot store the job: ") + e.what());
  }
  log_.info("job {} accepted from {} (user {}): '{}', priority {}, seed {}", job, c->peer().name, c->user, s.name,
            s.priority, s.seed);
  protocol::Accepted a;
  a.id = s.id;
  a.job = job;
  c->send(protocol::encode(a));
  dirty_.insert(conn);
  if (r.workers > 0) {
    try {
      r.id = job;
      load_work_job(r);
    } catch (const std::exception& e) {
      log_.error("job {}: cannot prepare its work units: {}", job, e.what());
    }
    dispatch_work();
    return;
  }
  reschedule();
}

void Server::reschedule() {
  try {
    reschedule_now();
    reschedule_pending_ = false;
  } catch (const std::exception& e) {
    if (!reschedule_pending_) log_.error("scheduling failed: {}; retrying every second", e.what());
    reschedule_pending_ = true;
  }
}

void Server::reschedule_now() {
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
    if (r.workers > 0) continue;        // rendered by omega workers (server_workers.cpp)
    queued.push_back(SchedJob{r.id, r.priority});
    by_id.emplace(r.id, r);
  }
  SchedDecision d = schedule(queued, running, cfg_.max_running - stopping, preempting);
  for (std::uint64_t id : d.preempt) {
    // The store first: if it refuses, the job keeps rendering and the store still says running.
    store_->set_state(id, JobState::queued);
    log_.info("job {}: preempted by a higher-priority job; back to the queue", id);
    active_.at(id).worker->request_stop(StopKind::preempt);
  }
  for (std::uint64_t id : d.start) start_job(by_id.at(id));
}

void Server::start_job(const JobRecord& r) {
  WorkerSpec spec;
  spec.job = r.id;
  spec.paths = paths(r.id);
  spec.name = r.name;
  spec.integrator = r.integrator;
  spec.sampler = r.sampler;
  spec.halt = r.halt;
  spec.seed = r.seed;
  spec.threads = cfg_.threads;
  spec.tile_size = cfg_.tile_size;
  spec.checkpoint_interval_s = cfg_.checkpoint_interval_s;
  spec.allowed_roots = cfg_.allowed_roots;
  spec.resume = memo_[r.id].snapshot;
  spec.share = &share_;
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
      },
      // Render threads, while someone watches: finished tiles go out in batches (tile_inbox.h).
      [this](TileUpdate t) { tile_inbox_.push(std::move(t)); });
  worker->set_watched(publisher_.watchers(r.id) > 0);
  store_->set_state(r.id, JobState::running);  // throws before the worker starts: still queued
  share_.add(r.id, share_weight(r.priority));
  publisher_.progress(r.id, JobState::running, r.progress);
  log_.info("job {}: started ('{}', priority {})", r.id, r.name, r.priority);
  worker->start();
  active_[r.id].worker = std::move(worker);
}

void Server::on_pass(PassUpdate u) {
  tile_inbox_.drain();  // the pass's streamed tiles go before its progress
  Memo& m = memo_[u.job];
  m.snapshot = u.snapshot;
  m.film = u.film;
  std::optional<JobRecord> r = store_->get(u.job);
  if (!r) return;
  // Progress rows are advisory (on_finish records the final one): a store that refuses them must
  // not block the loop for its busy timeout at every pass, nor stop the tiles.
  if (const auto now = std::chrono::steady_clock::now(); now >= progress_backoff_until_) {
    try {
      store_->set_progress(u.job, u.progress);
    } catch (const std::exception& e) {
      progress_backoff_until_ = now + std::chrono::seconds(10);
      log_.warn("job {}: cannot record progress in the job store: {}; rendering on, next try in 10 s", u.job, e.what());
    }
  }
  if (!u.tiles.empty()) publisher_.update_tiles(u.job, u.tiles, u.progress.pass, u.progress.spp);
  if (u.tiles_streamed) publisher_.tiles_complete(u.job, u.progress.spp);
  publisher_.progress(u.job, r->state, u.progress);
  log_.debug("job {}: pass {} done, {} spp, {:.2f} s", u.job, u.progress.pass, u.progress.spp, u.progress.elapsed_s);
}

void Server::on_tile(TileUpdate t) {
  if (active_.find(t.job) == active_.end()) return;  // the job stopped since: its boundary rules
  publisher_.update_tile(t.job, t.tile, t.pass, t.spp);
}

void Server::on_finish(WorkerResult res) {
  tile_inbox_.drain();  // the last pass's tiles go before done
  auto it = active_.find(res.job);
  if (it != active_.end()) {
    it->second.worker->join();
    active_.erase(it);
    share_.remove(res.job);
  }
  if (res.last) memo_[res.job].snapshot = res.last;
  try {
    record_finish(res);
  } catch (const std::exception& e) {
    // Without this the row would say running until the next restart (nothing else rewrites it).
    log_.error("job {}: cannot record its end in the job store: {}; retrying every second (it shows as running "
               "until then)",
               res.job, e.what());
    unrecorded_[res.job] = std::move(res);
  }
  reschedule();
  maybe_finish_shutdown();
}

void Server::record_finish(const WorkerResult& res) {
  std::optional<JobRecord> r = store_->get(res.job);
  if (!r) return;  // deleted meanwhile
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
        store_->set_outcome(res.job, JobState::done, p);
        publisher_.done(res.job, JobState::done, p, std::nullopt);
        log_.info("job {}: done: {} spp in {:.2f} s", res.job, p.spp, p.elapsed_s);
      }
      memo_.erase(res.job);  // result.exr and the final checkpoint serve it from now on
      break;
    case WorkerResult::Outcome::failed: {
      const std::string shown = redact_state_paths(res.message, cfg_.state_dir);  // job_info and done frames
      store_->set_outcome(res.job, JobState::failed, p, shown);
      publisher_.done(res.job, JobState::failed, p, shown);
      log_.error("job {}: failed: {}", res.job, res.message);
      break;
    }
    case WorkerResult::Outcome::stopped: {
      // pause, cancel and preempt wrote their state before asking the worker to stop; a row that
      // still says running (a write lost some other way) gets the state the stop stands for.
      // drain and now leave it running: the next start queues it again (recover_jobs).
      std::optional<JobState> want;
      if (r->state == JobState::running) {
        if (res.stop == StopKind::pause) want = JobState::paused;
        if (res.stop == StopKind::cancel) want = JobState::cancelled;
        if (res.stop == StopKind::preempt) want = JobState::queued;
      }
      if (want) {
        store_->set_outcome(res.job, *want, p);
        log_.warn("job {}: the store still said running after a {} stop; recorded {}", res.job, to_string(res.stop),
                  protocol::to_string(*want));
        r->state = *want;
      }
      log_.info("job {}: stopped ({}) at {} spp", res.job, to_string(res.stop), p.spp);
      if (res.stop == StopKind::pause || res.stop == StopKind::preempt) publisher_.progress(res.job, r->state, p);
      break;
    }
  }
}

void Server::retry_store() {
  if (!unrecorded_.empty()) {
    JobStore::QuickBusy quick(*store_);  // a retry must not block the loop for the full busy timeout
    for (auto it = unrecorded_.begin(); it != unrecorded_.end();) {
      try {
        record_finish(it->second);
        log_.info("job {}: its end is recorded in the job store now", it->first);
        it = unrecorded_.erase(it);
        reschedule_pending_ = true;  // its slot and its state may let a queued job start
      } catch (const std::exception&) {
        ++it;  // logged at the first failure; the next second tries again
      }
    }
  }
  if (reschedule_pending_) {
    JobStore::QuickBusy quick(*store_);
    reschedule();
    maybe_finish_shutdown();
  }
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
