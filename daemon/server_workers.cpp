// Work units for `omega worker`s (docs/farm.md "Workers"): hand-out by priority, results stored
// and recorded before they count, the in-order fold, and stops. Loop thread unless noted.
//
// The rule that keeps the image exact: a unit's part is written and fsynced under the job's
// units/ folder, then the unit is recorded done in the store (once: a done unit never changes),
// then it is handed to the fold, which merges done units strictly in sample order. After a crash
// the fold is rebuilt from the done units' files, so nothing is counted twice or lost.
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>

#include "daemon/server.h"

namespace omega::daemon {

namespace fs = std::filesystem;
using protocol::ErrorCode;
using protocol::JobState;

namespace {

// Any thread: renames and fsyncs the directory, so the new name survives a crash.
void rename_durable(const std::string& from, const std::string& to) {
  fs::rename(from, to);
  const std::string dir = fs::path(to).parent_path().string();
  int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd >= 0) {
    ::fsync(fd);
    ::close(fd);
  }
}

std::string range_text(std::uint64_t b, std::uint64_t e) { return std::to_string(b) + ":" + std::to_string(e); }

}  // namespace

bool Server::may_work(const Connection& c) const {
  if (c.worker_role) return true;
  if (c.peer().uid && (*c.peer().uid == 0 || *c.peer().uid == ::getuid())) return true;
  if (c.user == "tcp") return true;  // loopback TCP without tcp_users: the one anonymous identity
  return std::find(cfg_.admins.begin(), cfg_.admins.end(), c.user) != cfg_.admins.end();
}

void Server::load_work_job(const JobRecord& r) {
  WorkJob w;
  w.units = store_->units(r.id);
  w.target = r.halt.spp ? *r.halt.spp : cfg_.max_spp;
  w.base_elapsed_s = r.progress.elapsed_s;
  const JobPaths jp = paths(r.id);
  w.scene = read_file(jp.scene());
  std::error_code ec;
  if (fs::exists(jp.dir + "/assets.txt", ec)) w.assets = parse_asset_list(read_file(jp.dir + "/assets.txt"));
  w.fold = std::make_shared<UnitFold>();
  std::size_t done = 0;
  for (const UnitRecord& u : w.units) done += u.state == UnitState::done;
  work_[r.id] = std::move(w);
  next_slurm_poll_ = {};  // executor slurm: start its workers at the next tick, not a poll_s later
  log_.info("job {}: on workers ({} wanted), {} unit(s) recorded, {} done", r.id, r.workers,
            work_[r.id].units.size(), done);
  advance_fold(r.id);
}

std::uint64_t Server::unit_size(const JobRecord& r, const WorkJob& w, const Connection& c) const {
  if (r.unit_spp > 0) return r.unit_spp;
  // About unit_seconds on this worker, from the job's measured speed; 1 spp until measured.
  std::uint64_t n = 1;
  if (w.spp_per_thread_s > 0)
    n = static_cast<std::uint64_t>(std::max(1.0, cfg_.unit_seconds * w.spp_per_thread_s * c.worker->threads));
  // The tail: no unit larger than a share of what is left, so workers finish together.
  const std::uint64_t next = w.units.empty() ? 0 : w.units.back().end;
  const std::uint64_t left = w.target > next ? w.target - next : 0;
  return std::max<std::uint64_t>(1, std::min(n, left / (2 * std::max<std::uint32_t>(1, r.workers)) + 1));
}

void Server::on_work_request(Connection& c, const protocol::WorkRequest& m) {
  if (!may_work(c)) {
    log_.warn("connection {} ({}): work_request from {} refused: not a worker", c.id(), c.peer().name, c.user);
    return reply_error(c, m.id, ErrorCode::permission_denied,
                       "work_request: " + c.user + " may not take work units (tcp_users role worker, or an admin)");
  }
  if (!c.worker) {
    c.worker.emplace();
    c.worker->name = "conn " + std::to_string(c.id()) + " (" + (m.name.empty() ? c.peer().name : m.name) + ")";
    log_.info("connection {} ({}): worker '{}' with {} thread(s)", c.id(), c.peer().name, c.worker->name, m.threads);
  }
  if (c.worker->waiting) return reply_error(c, m.id, ErrorCode::bad_request, "work_request: one is already waiting");
  c.worker->threads = m.threads;
  c.worker->waiting = m.id;
  dispatch_work();
}

void Server::dispatch_work() {
  if (phase_ != Phase::serving) return;
  for (auto& [id, conn] : conns_) {
    Connection& c = *conn;
    if (!c.worker || !c.worker->waiting || c.closing || c.dead) continue;
    try {
      if (!assign_unit(c)) return;  // nothing to hand out: the other waiting workers get nothing either
    } catch (const std::exception& e) {
      log_.error("work units: cannot hand out a unit: {}; retrying every second", e.what());
      return;
    }
  }
}

bool Server::assign_unit(Connection& c) {
  std::vector<JobRecord> jobs;
  for (auto& [id, w] : work_) {
    if (w.finishing) continue;
    std::optional<JobRecord> r = store_->get(id);
    if (r && (r->state == JobState::queued || r->state == JobState::running)) jobs.push_back(std::move(*r));
  }
  std::stable_sort(jobs.begin(), jobs.end(), [](const JobRecord& a, const JobRecord& b) {
    return a.priority != b.priority ? a.priority > b.priority : a.id < b.id;
  });
  for (const JobRecord& r : jobs) {
    WorkJob& w = work_.at(r.id);
    // Any connected worker may take any job's units: `workers` is how many omegad starts itself
    // (executor slurm) and sizes the tail, not a cap, so a worker started by hand always helps.
    std::optional<std::size_t> queued;
    for (std::size_t i = 0; i < w.units.size() && !queued; ++i)
      if (w.units[i].state == UnitState::queued) queued = i;
    UnitRecord u;
    if (queued) {
      u = w.units[*queued];
    } else {
      const std::uint64_t next = w.units.empty() ? 0 : w.units.back().end;
      if (next >= w.target) continue;
      u.job = r.id;
      u.unit = w.units.size();
      u.begin = next;
      u.end = std::min(w.target, next + unit_size(r, w, c));
    }
    u.state = UnitState::running;
    u.owner = c.worker->name;
    store_->put_unit(u);  // recorded before it goes out; throws with nothing changed
    if (r.state == JobState::queued) {
      store_->set_state(r.id, JobState::running);
      publisher_.progress(r.id, JobState::running, r.progress);
    }
    if (u.unit == w.units.size()) w.units.push_back(u);
    else w.units[u.unit] = u;
    if (!w.started) w.started = std::chrono::steady_clock::now();
    c.worker->units.insert({r.id, u.unit});
    protocol::WorkUnit m;
    m.id = *c.worker->waiting;
    c.worker->waiting.reset();
    m.job = r.id;
    m.unit = u.unit;
    m.begin = u.begin;
    m.end = u.end;
    m.seed = r.seed;
    m.name = r.name;
    if (!r.integrator.empty()) m.integrator = r.integrator;
    if (!r.sampler.empty()) m.sampler = r.sampler;
    m.assets = w.assets;
    m.scene = w.scene;
    c.send(protocol::encode(m));
    dirty_.insert(c.id());
    log_.info("job {}: unit {} (samples {}) to {}", r.id, u.unit, range_text(u.begin, u.end), c.worker->name);
    return true;
  }
  return false;
}

void Server::on_asset_request(Connection& c, const protocol::AssetRequest& m) {
  auto w = work_.find(m.job);
  const protocol::AssetRef* ref = nullptr;
  bool holds = false;
  if (c.worker)
    for (const auto& [job, unit] : c.worker->units) holds |= job == m.job;
  if (holds && w != work_.end())
    for (const auto& a : w->second.assets)
      if (a.sha256 == m.sha256) ref = &a;
  if (!ref) {
    log_.warn("connection {} ({}): asset_request {} of job {} refused", c.id(), c.peer().name, m.sha256, m.job);
    return reply_error(c, m.id, ErrorCode::permission_denied,
                       "asset_request: this worker holds no unit of job " + std::to_string(m.job) +
                           " whose scene uses asset " + m.sha256);
  }
  const std::string file = paths(m.job).files() + "/" + ref->name;
  background_.submit([this, conn = c.id(), m, file] {  // background thread: the read
    protocol::Asset a;
    a.id = m.id;
    a.sha256 = m.sha256;
    std::string err;
    try {
      a.data = read_file(file);
    } catch (const std::exception& e) {
      err = e.what();
    }
    loop_.post([this, conn, a = std::move(a), err] {
      Connection* c = find(conn);
      if (!c) return;
      if (!err.empty()) reply_error(*c, a.id, ErrorCode::internal, "asset_request: " + err);
      else c->send(protocol::encode(a));
      dirty_.insert(conn);
      flush_dirty();
    });
  });
}

void Server::on_unit_result(Connection& c, protocol::UnitResult m) {
  auto it = work_.find(m.job);
  if (it == work_.end() || it->second.finishing)
    return reply_error(c, m.id, ErrorCode::invalid_state,
                       "unit_result: job " + std::to_string(m.job) + " takes no units (finished, cancelled or unknown)");
  WorkJob& w = it->second;
  if (m.unit >= w.units.size() || w.units[m.unit].begin != m.begin || w.units[m.unit].end != m.end)
    return reply_error(c, m.id, ErrorCode::bad_request,
                       "unit_result: job " + std::to_string(m.job) + " has no unit " + std::to_string(m.unit) +
                           " of samples " + range_text(m.begin, m.end));
  if (w.units[m.unit].state == UnitState::done)
    return reply_error(c, m.id, ErrorCode::invalid_state,
                       "unit_result: unit " + std::to_string(m.unit) + " of job " + std::to_string(m.job) +
                           " is merged already");
  std::optional<JobRecord> r = store_->get(m.job);
  if (!r) return reply_error(c, m.id, ErrorCode::unknown_job, "no job " + std::to_string(m.job));
  const JobPaths jp = paths(m.job);
  const std::string final_path = unit_part_path(jp, m.unit);
  const std::string tmp = final_path + ".conn" + std::to_string(c.id());
  auto fold = w.fold;
  std::vector<std::string> roots = cfg_.allowed_roots;
  // Background thread: the part goes to disk and is checked before the loop counts it.
  background_.submit([this, conn = c.id(), m = std::move(m), jp, final_path, tmp, fold, rec = *r, roots]() mutable {
    std::string err;
    try {
      fs::create_directories(jp.dir + "/units");
      write_file_atomic(tmp, m.part);
      init_fold(*fold, jp, rec.name, rec.integrator, rec.sampler, rec.seed, roots);
      check_part(*fold, tmp, m.begin, m.end);
      rename_durable(tmp, final_path);
    } catch (const std::exception& e) {
      err = e.what();
      std::error_code ec;
      fs::remove(tmp, ec);
      fs::remove(tmp + ".tmp", ec);
    }
    m.part.clear();
    loop_.post([this, conn, m = std::move(m), err] {
      on_unit_stored(conn, m, err);
      flush_dirty();
    });
  });
}

void Server::on_unit_stored(std::uint64_t conn, const protocol::UnitResult& m, const std::string& error) {
  Connection* c = find(conn);
  auto it = work_.find(m.job);
  auto requeue_mine = [&] {
    if (c && c->worker && c->worker->units.erase({m.job, m.unit}) && it != work_.end()) {
      UnitRecord& u = it->second.units[m.unit];
      if (u.state == UnitState::running) {
        UnitRecord q = u;
        q.state = UnitState::queued;
        q.owner.clear();
        try {
          store_->put_unit(q);
          u = q;
        } catch (const std::exception& e) {
          log_.error("job {}: cannot requeue unit {}: {}", m.job, m.unit, e.what());
        }
      }
    }
  };
  if (!error.empty()) {
    log_.warn("job {}: unit {} from {} refused: {}", m.job, m.unit, c && c->worker ? c->worker->name : "a gone worker",
              error);
    if (c) reply_error(*c, m.id, ErrorCode::bad_request, "unit_result: " + error);
    requeue_mine();
    dispatch_work();
    return;
  }
  if (it == work_.end() || it->second.finishing || it->second.units[m.unit].state == UnitState::done) {
    if (c) reply_error(*c, m.id, ErrorCode::invalid_state, "unit_result: the unit is not wanted any more");
    if (c && c->worker) c->worker->units.erase({m.job, m.unit});
    return;
  }
  WorkJob& w = it->second;
  UnitRecord u = w.units[m.unit];
  u.state = UnitState::done;
  u.owner.clear();
  u.time_s = m.time_s;
  try {
    store_->put_unit(u);  // from here on the unit counts, exactly once
  } catch (const std::exception& e) {
    log_.error("job {}: cannot record unit {} done: {}", m.job, m.unit, e.what());
    if (c) reply_error(*c, m.id, store_error_code(e.what()), std::string("unit_result: ") + e.what());
    requeue_mine();
    return;
  }
  w.units[m.unit] = u;
  // Whoever else renders this unit (handed out again while this result was under way) stops.
  for (auto& [id, other] : conns_) {
    if (!other->worker || !other->worker->units.erase({m.job, m.unit}) || id == conn) continue;
    other->send(protocol::encode(protocol::UnitStop{0, m.job, m.unit, "merged from another worker"}));
    dirty_.insert(id);
  }
  if (c && c->worker) {
    c->worker->done[m.job] += 1;
    c->worker->samples_per_s = m.samples_per_s;
    if (m.time_s > 0)
      w.spp_per_thread_s = double(m.end - m.begin) / m.time_s / double(std::max<std::uint32_t>(1, c->worker->threads));
    c->send(protocol::encode(protocol::Ok{m.id}));
    dirty_.insert(conn);
  }
  log_.info("job {}: unit {} (samples {}) done by {} in {:.2f} s", m.job, m.unit, range_text(m.begin, m.end),
            c && c->worker ? c->worker->name : "a gone worker", m.time_s);
  advance_fold(m.job);
  dispatch_work();
}

void Server::advance_fold(std::uint64_t job) {
  auto it = work_.find(job);
  if (it == work_.end() || it->second.finishing) return;
  WorkJob& w = it->second;
  const JobPaths jp = paths(job);
  std::vector<std::string> files;
  while (w.next_fold < w.units.size() && w.units[w.next_fold].state == UnitState::done && w.fold_end < w.target) {
    files.push_back(unit_part_path(jp, w.next_fold));
    w.fold_end = w.units[w.next_fold].end;
    ++w.next_fold;
  }
  if (!files.empty()) {
    std::optional<JobRecord> r = store_->get(job);
    if (!r) return;
    const bool watched = publisher_.watchers(job) > 0;
    auto fold = w.fold;
    std::vector<std::string> roots = cfg_.allowed_roots;
    const int tile = cfg_.tile_size;
    background_.submit([this, job, jp, files, fold, rec = *r, roots, watched, tile] {  // background thread
      FoldUpdate u;
      try {
        init_fold(*fold, jp, rec.name, rec.integrator, rec.sampler, rec.seed, roots);
        u = fold_parts(*fold, job, files, watched, tile);
      } catch (const std::exception& e) {
        u.job = job;
        u.error = e.what();
      }
      loop_.post([this, u = std::move(u)]() mutable {
        on_fold(std::move(u));
        flush_dirty();
      });
    });
  }
  if (w.fold_end >= w.target) finish_work_job(job, "all samples merged");
}

void Server::on_fold(FoldUpdate u) {
  auto it = work_.find(u.job);
  if (it == work_.end()) return;  // cancelled or deleted meanwhile
  WorkJob& w = it->second;
  if (!u.error.empty()) return on_work_done(u.job, 0, "merging a unit failed: " + u.error);
  std::optional<JobRecord> r = store_->get(u.job);
  if (!r) return;
  PassUpdate p;
  p.job = u.job;
  p.snapshot = u.snapshot;
  p.film = u.film;
  p.tiles = std::move(u.tiles);
  p.progress.pass = u.snapshot->pass;
  p.progress.spp = u.snapshot->spp;
  p.progress.rel_error = u.snapshot->rel_error;
  const double since = w.started ? std::chrono::duration<double>(std::chrono::steady_clock::now() - *w.started).count() : 0;
  p.progress.elapsed_s = w.base_elapsed_s + since;
  for (const auto& [id, c] : conns_)
    if (c->worker)
      for (const auto& [job, unit] : c->worker->units)
        if (job == u.job) {
          p.progress.samples_per_s += c->worker->samples_per_s;
          break;
        }
  const bool halt_error = r->halt.target_error && u.snapshot->rel_error && *u.snapshot->rel_error <= *r->halt.target_error;
  const bool halt_time = r->halt.time_s && p.progress.elapsed_s >= *r->halt.time_s;
  on_pass(std::move(p));
  if (!w.finishing && (halt_error || halt_time)) {
    w.target = w.fold_end;  // what is handed to the fold is the result; nothing after it
    finish_work_job(u.job, halt_error ? "target error reached" : "time limit reached");
  }
}

void Server::finish_work_job(std::uint64_t job, const std::string& why) {
  WorkJob& w = work_.at(job);
  w.finishing = true;
  stop_units(job, why);
  std::optional<JobRecord> r = store_->get(job);
  if (!r) return;
  const JobPaths jp = paths(job);
  auto fold = w.fold;
  std::vector<std::string> roots = cfg_.allowed_roots;
  log_.info("job {}: {}; writing the result ({} spp)", job, why, w.fold_end);
  // Background thread, after every fold task submitted before it (tasks run in order).
  background_.submit([this, job, jp, fold, rec = *r, roots] {
    std::string err;
    std::uint64_t spp = 0;
    try {
      init_fold(*fold, jp, rec.name, rec.integrator, rec.sampler, rec.seed, roots);
      write_fold_result(*fold, jp.result());
      spp = fold->spp;
    } catch (const std::exception& e) {
      err = e.what();
    }
    loop_.post([this, job, spp, err] {
      on_work_done(job, spp, err);
      flush_dirty();
    });
  });
}

void Server::on_work_done(std::uint64_t job, std::uint64_t spp, const std::string& error) {
  auto it = work_.find(job);
  if (it == work_.end()) return;
  stop_units(job, error.empty() ? "job done" : "job failed");
  work_.erase(it);
  stop_slurm_workers(job, error.empty() ? "job done" : "job failed");
  std::optional<JobRecord> r = store_->get(job);
  if (!r || protocol::is_terminal(r->state)) return;
  protocol::ProgressInfo p = r->progress;
  p.samples_per_s = 0;
  if (error.empty()) p.spp = spp;
  try {
    const std::string shown = redact_state_paths(error, cfg_.state_dir);
    store_->set_outcome(job, error.empty() ? JobState::done : JobState::failed, p, shown);
    publisher_.done(job, error.empty() ? JobState::done : JobState::failed, p,
                    error.empty() ? std::nullopt : std::optional(shown));
  } catch (const std::exception& e) {
    log_.error("job {}: cannot record its end: {}", job, e.what());  // recovery redoes the fold and the result
    return;
  }
  if (error.empty()) {
    memo_.erase(job);  // result.exr serves it from now on
    log_.info("job {}: done on workers: {} spp", job, spp);
  } else {
    log_.error("job {}: failed: {}", job, error);
  }
}

void Server::stop_units(std::uint64_t job, const std::string& reason) {
  auto it = work_.find(job);
  for (auto& [id, c] : conns_) {
    if (!c->worker) continue;
    for (auto u = c->worker->units.begin(); u != c->worker->units.end();) {
      if (u->first != job) {
        ++u;
        continue;
      }
      c->send(protocol::encode(protocol::UnitStop{0, job, u->second, reason}));
      dirty_.insert(id);
      u = c->worker->units.erase(u);
    }
  }
  if (it == work_.end()) return;
  for (UnitRecord& u : it->second.units) {
    if (u.state != UnitState::running) continue;
    requeue_unit(job, u);
  }
}

void Server::requeue_unit(std::uint64_t job, UnitRecord& u) {
  UnitRecord q = u;
  q.state = UnitState::queued;
  q.owner.clear();
  try {
    store_->put_unit(q);
  } catch (const std::exception& e) {
    log_.error("job {}: cannot requeue unit {}: {} (the next start does)", job, u.unit, e.what());
  }
  u = q;
}

void Server::release_worker_units(Connection& c) {
  if (!c.worker) return;
  for (const auto& [job, unit] : c.worker->units) {
    auto it = work_.find(job);
    if (it == work_.end() || unit >= it->second.units.size()) continue;
    UnitRecord& u = it->second.units[unit];
    if (u.state != UnitState::running) continue;
    requeue_unit(job, u);
    log_.info("job {}: unit {} (samples {}) back to the queue: {} left", job, unit, range_text(u.begin, u.end),
              c.worker->name);
  }
  c.worker->units.clear();
}

protocol::JobInfo Server::job_info(const JobRecord& r) const {
  protocol::JobInfo i = r.info();
  if (r.workers == 0) return i;
  double rate = 0;
  for (const auto& [id, c] : conns_) {
    if (!c->worker) continue;
    protocol::WorkerInfo wi;
    wi.name = c->worker->name;
    auto d = c->worker->done.find(r.id);
    wi.units_done = d == c->worker->done.end() ? 0 : d->second;
    auto w = work_.find(r.id);
    for (const auto& [job, unit] : c->worker->units)
      if (job == r.id && w != work_.end() && unit < w->second.units.size())
        wi.units.push_back(range_text(w->second.units[unit].begin, w->second.units[unit].end));
    if (wi.units_done == 0 && wi.units.empty()) continue;
    wi.samples_per_s = c->worker->samples_per_s;
    if (!wi.units.empty()) rate += wi.samples_per_s;
    i.workers.push_back(std::move(wi));
  }
  if (!protocol::is_terminal(r.state)) i.progress.samples_per_s = rate;
  return i;
}

}  // namespace omega::daemon
