// Protocol request handlers. Loop thread.
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <variant>

#include "daemon/server.h"
#include "daemon/tcp_auth.h"
#include "film/film.h"

namespace omega::daemon {

namespace fs = std::filesystem;
using protocol::ErrorCode;
using protocol::JobState;
using protocol::MessageType;

void Server::reply_error(Connection& c, std::uint64_t id, ErrorCode code, const std::string& msg) {
  protocol::Error e;
  e.id = id;
  e.code = code;
  const std::string safe = redact_state_paths(msg, cfg_.state_dir);  // no daemon path reaches a client
  e.message = safe.size() > protocol::kMaxMessageBytes ? safe.substr(0, protocol::kMaxMessageBytes) : safe;
  c.send(protocol::encode(e));
  dirty_.insert(c.id());
}

bool Server::may_access(const Connection& c, const JobRecord& r) const {
  if (c.user == r.owner) return true;
  if (c.peer().uid && (*c.peer().uid == 0 || *c.peer().uid == ::getuid())) return true;  // root and the daemon's user
  for (const auto& a : cfg_.admins)
    if (a == c.user) return true;
  return false;
}

std::size_t Server::recent_auth_failures(const std::string& address, std::chrono::steady_clock::time_point now) {
  auto it = auth_failures_.find(address);
  if (it == auth_failures_.end()) return 0;
  auto& times = it->second;
  while (!times.empty() && now - times.front() >= std::chrono::seconds(60)) times.pop_front();
  if (times.empty()) {
    auth_failures_.erase(it);
    return 0;
  }
  return times.size();
}

bool Server::tcp_auth_required(const Connection& c) const { return !c.peer().unix_socket && !cfg_.tcp_users.empty(); }

void Server::deny(Connection& c, std::uint64_t id, std::string_view what, const JobRecord& r) {
  log_.warn("connection {} ({}): {} of job {} denied: it belongs to {}, not {}", c.id(), c.peer().name, what, r.id,
            r.owner, c.user);
  reply_error(c, id, ErrorCode::permission_denied,
              std::string(what) + ": job " + std::to_string(r.id) + " belongs to " + r.owner + ", not " + c.user);
}

void Server::on_auth(Connection& c, const protocol::DecodedFrame& f) {
  auto a = protocol::decode<protocol::Auth>(f);
  if (!a) {
    reply_error(c, f.id, ErrorCode::bad_request, a.message());
    c.closing = true;
    return;
  }
  const auto now = std::chrono::steady_clock::now();
  if (cfg_.auth_fail_limit > 0) {
    // Too many failures from this address in the last minute: refuse without checking the MAC,
    // so guessing tokens runs at auth_fail_limit tries per minute at most. Refusals do not count.
    const std::size_t n = recent_auth_failures(c.peer().address, now);
    if (n >= static_cast<std::size_t>(cfg_.auth_fail_limit)) {
      const double wait = 60.0 - std::chrono::duration<double>(now - auth_failures_[c.peer().address].front()).count();
      log_.warn("connection {} ({}): authentication as '{}' refused: {} failed attempts from {} in the last minute "
                "(auth_fail_limit {}); closing",
                c.id(), c.peer().name, a->user.substr(0, 256), n, c.peer().address, cfg_.auth_fail_limit);
      reply_error(c, f.id, ErrorCode::auth_failed,
                  fmt::format("too many failed authentications from {}: {} in the last minute (auth_fail_limit {}); "
                              "try again in {:.0f} s",
                              c.peer().address, n, cfg_.auth_fail_limit, std::max(1.0, std::ceil(wait))));
      c.closing = true;
      return;
    }
  }
  if (!check_auth(cfg_.tcp_users, c.nonce, a->user, a->mac)) {
    if (cfg_.auth_fail_limit > 0) {
      if (!auth_failures_.count(c.peer().address) && auth_failures_.size() >= kMaxAuthFailAddresses)
        auth_failures_.erase(auth_failures_.begin());  // bounded memory against many source addresses
      auto& times = auth_failures_[c.peer().address];
      times.push_back(now);
      while (times.size() > static_cast<std::size_t>(cfg_.auth_fail_limit)) times.pop_front();
    }
    log_.warn("connection {} ({}): authentication failed for user '{}'; closing", c.id(), c.peer().name,
              a->user.substr(0, 256));
    reply_error(c, f.id, ErrorCode::auth_failed, "authentication failed: unknown user or wrong token");
    c.closing = true;
    return;
  }
  c.user = a->user;
  c.authenticated = true;
  c.worker_role = cfg_.worker_users.count(c.user) > 0;
  c.nonce.clear();
  c.send(protocol::encode(protocol::Ok{f.id}));
  log_.info("connection {} ({}): authenticated as '{}'", c.id(), c.peer().name, c.user);
}

void Server::handle_frame(Connection& c, protocol::DecodedFrame& f) {
  dirty_.insert(c.id());
  if (!c.welcomed) {
    if (f.type != MessageType::hello) {
      log_.warn("connection {} ({}): '{}' before hello; closing", c.id(), c.peer().name, protocol::to_string(f.type));
      reply_error(c, f.id, ErrorCode::auth_required, "the session must open with hello");
      c.closing = true;
      return;
    }
    auto h = protocol::decode<protocol::Hello>(f);
    if (!h) {
      reply_error(c, f.id, ErrorCode::bad_request, h.message());
      c.closing = true;
      return;
    }
    auto v = protocol::negotiate_version(h->min_version, h->version);
    if (!v) {
      log_.warn("connection {} ({}): no common protocol version (client {}..{})", c.id(), c.peer().name,
                h->min_version, h->version);
      reply_error(c, f.id, ErrorCode::unsupported_version,
                  "omegad speaks protocol versions " + std::to_string(protocol::kMinProtocolVersion) + ".." +
                      std::to_string(protocol::kProtocolVersion));
      c.closing = true;
      return;
    }
    protocol::Welcome w;
    w.id = f.id;
    w.version = *v;
    w.server = "omegad/0.1";
    if (c.peer().unix_socket) {
      if (!c.peer().uid) {
        log_.warn("connection {} ({}): no peer credentials; closing", c.id(), c.peer().name);
        reply_error(c, f.id, ErrorCode::auth_failed, "cannot read the peer's credentials (SO_PEERCRED)");
        c.closing = true;
        return;
      }
      w.auth = protocol::AuthMethod::peer;
      c.user = std::to_string(*c.peer().uid);
      w.user = c.user;
      c.authenticated = true;
    } else if (tcp_auth_required(c)) {
      w.auth = protocol::AuthMethod::hmac_sha256;
      c.nonce = make_nonce();
      w.nonce = c.nonce;
    } else {
      // Loopback TCP with no tcp_users configured (tests): one anonymous identity, "tcp".
      w.auth = protocol::AuthMethod::none;
      c.user = "tcp";
      w.user = c.user;
      c.authenticated = true;
    }
    c.welcomed = true;
    c.send(protocol::encode(w));
    log_.debug("connection {} ({}): hello from '{}', user {}", c.id(), c.peer().name, h->client, c.user);
    return;
  }

  if (!c.authenticated) {
    if (f.type == MessageType::auth) return on_auth(c, f);
    log_.warn("connection {} ({}): '{}' before authentication", c.id(), c.peer().name, protocol::to_string(f.type));
    return reply_error(c, f.id, ErrorCode::auth_required, "authenticate first (auth with the HMAC of the nonce)");
  }
  auto m = protocol::decode_message(f);
  if (!m) {
    log_.warn("connection {} ({}): bad {} request: {}: {}", c.id(), c.peer().name, protocol::to_string(f.type),
              protocol::to_string(m.code()), m.message());
    reply_error(c, f.id, ErrorCode::bad_request, std::string(protocol::to_string(m.code())) + ": " + m.message());
    return;
  }
  // A request that hits a store error (SQLite locked past its busy timeout, disk I/O) gets an
  // error frame naming it; the handlers write the store before acting, so nothing half happened.
  try {
    dispatch(c, f, *m);
  } catch (const std::exception& e) {
    log_.error("connection {} ({}): {} request failed: {}", c.id(), c.peer().name, protocol::to_string(f.type),
               e.what());
    reply_error(c, f.id, store_error_code(e.what()), std::string(protocol::to_string(f.type)) + ": " + e.what());
  }
}

void Server::dispatch(Connection& c, const protocol::DecodedFrame& f, protocol::Message& m) {
  if (c.worker_role && !std::holds_alternative<protocol::Ping>(m) && !std::holds_alternative<protocol::Pong>(m) &&
      !std::holds_alternative<protocol::Bye>(m) && !std::holds_alternative<protocol::WorkRequest>(m) &&
      !std::holds_alternative<protocol::AssetRequest>(m) && !std::holds_alternative<protocol::UnitResult>(m)) {
    log_.warn("connection {} ({}): '{}' from worker {} refused", c.id(), c.peer().name, protocol::to_string(f.type), c.user);
    return reply_error(c, f.id, ErrorCode::permission_denied,
                       std::string(protocol::to_string(f.type)) + ": " + c.user +
                           " is a worker: it may only take work units and their assets");
  }
  std::visit(
      [&](auto& msg) {
        using T = std::decay_t<decltype(msg)>;
        if constexpr (std::is_same_v<T, protocol::Ping>) {
          c.send(protocol::encode(protocol::Pong{msg.id}));
        } else if constexpr (std::is_same_v<T, protocol::Pong>) {
        } else if constexpr (std::is_same_v<T, protocol::Bye>) {
          c.closing = true;
        } else if constexpr (std::is_same_v<T, protocol::Submit>) {
          on_submit(c, std::move(msg));
        } else if constexpr (std::is_same_v<T, protocol::Asset>) {
          on_asset(c, std::move(msg));
        } else if constexpr (std::is_same_v<T, protocol::Status>) {
          on_job_request(c, MessageType::status, msg.id, msg.job, std::nullopt);
        } else if constexpr (std::is_same_v<T, protocol::List>) {
          protocol::JobList l;
          l.id = msg.id;
          for (const JobRecord& r : store_->all()) l.jobs.push_back(job_info(r));
          c.send(protocol::encode(l));
        } else if constexpr (std::is_same_v<T, protocol::SetPriority>) {
          on_job_request(c, MessageType::set_priority, msg.id, msg.job, msg.priority);
        } else if constexpr (std::is_same_v<T, protocol::Cancel> || std::is_same_v<T, protocol::Pause> ||
                             std::is_same_v<T, protocol::Resume> || std::is_same_v<T, protocol::Delete>) {
          on_job_request(c, T::kType, msg.id, msg.job, std::nullopt);
        } else if constexpr (std::is_same_v<T, protocol::Subscribe>) {
          on_subscribe(c, msg.id, msg.job);
        } else if constexpr (std::is_same_v<T, protocol::Unsubscribe>) {
          publisher_.unsubscribe(msg.job, c.id(), msg.id);
          update_watched(msg.job);
          c.send(protocol::encode(protocol::Ok{msg.id}));
        } else if constexpr (std::is_same_v<T, protocol::Fetch>) {
          on_fetch(c, msg.id, msg.job);
        } else if constexpr (std::is_same_v<T, protocol::WorkRequest>) {
          on_work_request(c, msg);
        } else if constexpr (std::is_same_v<T, protocol::AssetRequest>) {
          if (!may_work(c)) return reply_error(c, msg.id, ErrorCode::permission_denied, "asset_request: not a worker");
          on_asset_request(c, msg);
        } else if constexpr (std::is_same_v<T, protocol::UnitResult>) {
          if (!may_work(c)) return reply_error(c, msg.id, ErrorCode::permission_denied, "unit_result: not a worker");
          on_unit_result(c, std::move(msg));
        } else if constexpr (std::is_same_v<T, protocol::Hello>) {
          reply_error(c, msg.id, ErrorCode::bad_request, "hello: the session is already open");
        } else if constexpr (std::is_same_v<T, protocol::Auth>) {
          reply_error(c, msg.id, ErrorCode::bad_request, "auth: this session is already authenticated");
        } else {
          log_.warn("connection {} ({}): '{}' is not a request", c.id(), c.peer().name, protocol::to_string(f.type));
          reply_error(c, f.id, ErrorCode::bad_request,
                      "'" + std::string(protocol::to_string(f.type)) + "' is sent by the daemon, not to it");
        }
      },
      m);
}

void Server::on_submit(Connection& c, protocol::Submit s) {
  if (phase_ != Phase::serving) return reply_error(c, s.id, ErrorCode::shutting_down, "omegad is shutting down");
  if (c.pending.count(s.id)) return reply_error(c, s.id, ErrorCode::bad_request, "a submit with this id is already in progress");
  if (c.pending.size() >= static_cast<std::size_t>(cfg_.max_pending_submits))
    return reply_error(c, s.id, ErrorCode::busy, "too many submits in progress on this connection");
  if (store_->count_unfinished() >= static_cast<std::size_t>(cfg_.max_queued_jobs))
    return reply_error(c, s.id, ErrorCode::busy, "the queue is full (max_queued_jobs)");
  if (std::size_t n = store_->count_unfinished(c.user) + c.pending.size(); n >= static_cast<std::size_t>(cfg_.max_jobs_per_owner)) {
    log_.warn("connection {} ({}): submit {} refused: {} has {} unfinished job(s) (max_jobs_per_owner {})", c.id(),
              c.peer().name, s.id, c.user, n, cfg_.max_jobs_per_owner);
    return reply_error(c, s.id, ErrorCode::busy,
                       "user " + c.user + " has " + std::to_string(n) + " unfinished jobs (max_jobs_per_owner " +
                           std::to_string(cfg_.max_jobs_per_owner) + ")");
  }
  if (s.halt.spp && *s.halt.spp > cfg_.max_spp)
    return reply_error(c, s.id, ErrorCode::bad_request,
                       "halt.spp " + std::to_string(*s.halt.spp) + " is over this daemon's max_spp (" +
                           std::to_string(cfg_.max_spp) + ")");
  if (s.halt.time_s && *s.halt.time_s > cfg_.max_time_s)
    return reply_error(c, s.id, ErrorCode::bad_request,
                       fmt::format("halt.time_s {} is over this daemon's max_time_s ({})", *s.halt.time_s, cfg_.max_time_s));
  PendingSubmit p;
  std::map<std::string, std::uint64_t> sizes;
  for (const auto& a : s.assets) {
    auto [it, fresh] = sizes.emplace(a.sha256, a.size);
    if (!fresh && it->second != a.size) {
      log_.warn("connection {} ({}): submit {} refused: asset {} listed with two sizes", c.id(), c.peer().name, s.id, a.sha256);
      return reply_error(c, s.id, ErrorCode::asset_mismatch, "asset " + a.sha256 + " is listed with two different sizes");
    }
    if (a.size > cfg_.max_asset_bytes)
      return reply_error(c, s.id, ErrorCode::asset_mismatch, "asset '" + a.name + "' is larger than max_asset_bytes");
    if (!assets_->has(a.sha256)) p.missing.insert(a.sha256);
  }
  protocol::NeedAssets need;
  need.id = s.id;
  need.missing.assign(p.missing.begin(), p.missing.end());
  c.send(protocol::encode(need));
  log_.debug("connection {}: submit {} '{}': {} asset(s), {} missing", c.id(), s.id, s.name, s.assets.size(), p.missing.size());
  std::uint64_t id = s.id;
  p.submit = std::move(s);
  c.pending.emplace(id, std::move(p));
  if (c.pending[id].missing.empty()) validate(c, id);
}

void Server::on_asset(Connection& c, protocol::Asset a) {
  auto it = c.pending.find(a.id);
  if (it == c.pending.end() || !it->second.missing.count(a.sha256)) {
    log_.warn("connection {} ({}): asset {} for submit {} was not requested", c.id(), c.peer().name, a.sha256, a.id);
    return reply_error(c, a.id, ErrorCode::asset_mismatch, "asset " + a.sha256 + " was not requested");
  }
  PendingSubmit& p = it->second;
  const protocol::AssetRef* ref = nullptr;
  for (const auto& r : p.submit.assets)
    if (r.sha256 == a.sha256) ref = &r;
  std::string problem;
  if (a.data.size() != ref->size) {
    problem = "asset '" + ref->name + "' has " + std::to_string(a.data.size()) + " bytes, the submit said " +
              std::to_string(ref->size);
  } else {
    std::string got = sha256_hex(a.data);
    if (got != a.sha256) problem = "asset '" + ref->name + "' hashes to " + got + ", not " + a.sha256;
  }
  if (problem.empty()) {
    try {
      assets_->put(a.sha256, a.data);
    } catch (const std::exception& e) {
      log_.error("asset cache: {}", e.what());
      c.pending.erase(it);
      return reply_error(c, a.id, ErrorCode::busy, std::string("cannot store the asset: ") + e.what());
    }
  }
  if (!problem.empty()) {
    log_.warn("connection {} ({}): submit {} refused: {}", c.id(), c.peer().name, a.id, problem);
    c.pending.erase(it);
    return reply_error(c, a.id, ErrorCode::asset_mismatch, problem);
  }
  p.missing.erase(a.sha256);
  enforce_asset_cache_limit();
  if (p.missing.empty()) validate(c, a.id);
}

void Server::enforce_asset_cache_limit() {
  std::set<std::string> keep;  // assets of submits in progress: checked as present, not yet linked
  for (const auto& [id, conn] : conns_)
    for (const auto& [sid, p] : conn->pending)
      for (const auto& a : p.submit.assets) keep.insert(a.sha256);
  for (const auto& sha : assets_->evict(cfg_.max_asset_cache_bytes, keep))
    log_.info("asset cache: evicted {} (least recently used, no job needs it; max_asset_cache_bytes {})", sha,
              cfg_.max_asset_cache_bytes);
}

void Server::on_job_request(Connection& c, MessageType t, std::uint64_t id, std::uint64_t job,
                            std::optional<std::int64_t> priority) {
  std::optional<JobRecord> r = store_->get(job);
  if (!r) return reply_error(c, id, ErrorCode::unknown_job, "no job " + std::to_string(job));
  if (t == MessageType::status) {
    protocol::JobInfoReply reply;
    reply.id = id;
    reply.info = job_info(*r);
    c.send(protocol::encode(reply));
    return;
  }
  if (!may_access(c, *r)) return deny(c, id, protocol::to_string(t), *r);
  const std::string what(protocol::to_string(t));
  auto bad_state = [&] {
    reply_error(c, id, ErrorCode::invalid_state,
                what + ": job " + std::to_string(job) + " is " + std::string(protocol::to_string(r->state)));
  };
  auto running = active_.find(job);
  const bool live = running != active_.end();
  switch (t) {
    // The store before the worker: if the write throws (SQLite locked), nothing has changed and
    // handle_frame answers with an error frame; the job renders on as before.
    case MessageType::cancel:
      if (protocol::is_terminal(r->state)) return bad_state();
      store_->set_state(job, JobState::cancelled);
      if (live) running->second.worker->request_stop(StopKind::cancel);
      if (is_worker_job(job)) {
        stop_units(job, "cancelled");
        work_.erase(job);
        stop_slurm_workers(job, "cancelled");
      }
      publisher_.done(job, JobState::cancelled, r->progress, std::nullopt);
      log_.info("job {}: cancelled by {}", job, c.user);
      break;
    case MessageType::pause:
      if (r->state != JobState::queued && r->state != JobState::running) return bad_state();
      store_->set_state(job, JobState::paused);
      if (live) running->second.worker->request_stop(StopKind::pause);
      if (is_worker_job(job)) {
        stop_units(job, "paused");
        stop_slurm_workers(job, "paused");  // resume starts them again (server_slurm.cpp)
      }
      publisher_.progress(job, JobState::paused, r->progress);
      log_.info("job {}: paused by {}", job, c.user);
      break;
    case MessageType::resume:
      if (r->state != JobState::paused) return bad_state();
      store_->set_state(job, JobState::queued);
      publisher_.progress(job, JobState::queued, r->progress);
      next_slurm_poll_ = {};  // executor slurm: its workers start again at the next tick
      log_.info("job {}: resumed by {}", job, c.user);
      break;
    case MessageType::set_priority:
      if (protocol::is_terminal(r->state)) return bad_state();
      store_->set_priority(job, *priority);
      share_.set_weight(job, share_weight(*priority));  // a running job's share changes at once
      log_.info("job {}: priority {} -> {} by {}", job, r->priority, *priority, c.user);
      break;
    case MessageType::delete_job: {
      if (live) return reply_error(c, id, ErrorCode::invalid_state, "delete: job " + std::to_string(job) + " is still stopping; cancel it and retry");
      if (!protocol::is_terminal(r->state)) publisher_.done(job, JobState::cancelled, r->progress, std::string("deleted"));
      if (is_worker_job(job)) {
        stop_units(job, "deleted");
        work_.erase(job);
        stop_slurm_workers(job, "deleted");
      }
      store_->remove(job);
      std::error_code ec;
      fs::remove_all(paths(job).dir, ec);
      publisher_.forget(job);
      memo_.erase(job);
      log_.info("job {}: deleted by {}", job, c.user);
      break;
    }
    default:
      return reply_error(c, id, ErrorCode::internal, "unhandled request");
  }
  c.send(protocol::encode(protocol::Ok{id}));
  reschedule();
  dispatch_work();  // a resumed or re-prioritised worker job
}

void Server::on_subscribe(Connection& c, std::uint64_t id, std::uint64_t job) {
  std::optional<JobRecord> r = store_->get(job);
  if (!r) return reply_error(c, id, ErrorCode::unknown_job, "no job " + std::to_string(job));
  if (!may_access(c, *r)) return deny(c, id, "subscribe", *r);
  c.send(protocol::encode(protocol::Ok{id}));
  std::shared_ptr<const FilmSnapshot> snap = latest_snapshot(job);
  auto subscribe_now = [this, job, id, conn = c.id()](const JobRecord& rec) {
    if (!find(conn)) return;
    if (protocol::is_terminal(rec.state)) {
      publisher_.done(job, rec.state, rec.progress, rec.message.empty() ? std::nullopt : std::optional(rec.message));
    } else {
      publisher_.progress(job, rec.state, rec.progress);
    }
    publisher_.subscribe(job, conn, id);
    update_watched(job);
    dirty_.insert(conn);
  };
  const bool stale = snap && snap->spp > publisher_.tiles_spp(job);
  if (!stale) {
    subscribe_now(*r);
    return;
  }
  // The tiles were not encoded while nobody watched: encode the newest film once for this
  // subscriber (and any later one), off the loop thread.
  std::optional<FilmDesc> film = memo_[job].film;
  JobPaths jp = paths(job);
  JobRecord rec = *r;
  int tile = cfg_.tile_size;
  std::vector<std::string> roots = cfg_.allowed_roots;
  background_.submit([this, snap, film, jp, rec, tile, roots, subscribe_now] {
    std::vector<EncodedTile> tiles;
    std::string err;
    try {
      FilmSnapshot meta = *snap;
      FilmDesc fd;
      if (film && !meta.integrator.empty()) {
        fd = *film;
      } else {
        // A checkpoint restored after a restart does not record which integrator made it.
        SceneDesc d = load_job_scene(jp, rec.name, rec.integrator, rec.sampler, roots);
        fd = d.sensor.film;
        meta.integrator = integrator_name(d.integrator.type);
      }
      meta.seed = rec.seed;
      Film f = Film::deserialize(fd, meta.film);
      tiles = encode_tiles(f, tile, meta, aov_films_of(fd, meta));
    } catch (const std::exception& e) {
      err = e.what();
    }
    loop_.post([this, snap, tiles = std::move(tiles), err, job = rec.id, subscribe_now] {
      if (!err.empty()) log_.error("job {}: cannot encode tiles for a subscriber: {}", job, err);
      publisher_.update_tiles(job, tiles, snap->pass, snap->spp);
      if (auto now = store_->get(job)) subscribe_now(*now);
      flush_dirty();
    });
  });
}

void Server::on_fetch(Connection& c, std::uint64_t id, std::uint64_t job) {
  std::optional<JobRecord> r = store_->get(job);
  if (!r) return reply_error(c, id, ErrorCode::unknown_job, "no job " + std::to_string(job));
  if (!may_access(c, *r)) return deny(c, id, "fetch", *r);
  JobPaths jp = paths(job);
  std::shared_ptr<const FilmSnapshot> snap;
  std::error_code ec;
  const bool have_result = r->state == JobState::done && fs::exists(jp.result(), ec);
  if (!have_result) {
    snap = latest_snapshot(job);
    if (!snap)
      return reply_error(c, id, ErrorCode::invalid_state,
                         "fetch: job " + std::to_string(job) + " has no image yet (no pass has completed)");
  }
  std::optional<FilmDesc> film = memo_[job].film;
  std::vector<std::string> roots = cfg_.allowed_roots;
  JobRecord rec = *r;
  std::uint64_t conn = c.id();
  background_.submit([this, conn, id, jp, rec, snap, film, roots, have_result] {
    protocol::Image img;
    img.id = id;
    img.job = rec.id;
    std::string err;
    try {
      if (have_result) {
        img.exr = read_file(jp.result());
        ExrImage e = decode_exr_memory(std::span(reinterpret_cast<const std::uint8_t*>(img.exr.data()), img.exr.size()),
                                       1LL << 40);
        img.width = std::uint32_t(e.display_width);
        img.height = std::uint32_t(e.display_height);
        img.pass = rec.progress.pass;
        img.spp = rec.progress.spp;
      } else {
        FilmDesc fd = film ? *film : load_job_scene(jp, rec.name, rec.integrator, rec.sampler, roots).sensor.film;
        Film f = Film::deserialize(fd, snap->film);
        img.exr = encode_image(f, *snap, aov_films_of(fd, *snap));
        img.width = std::uint32_t(f.width());
        img.height = std::uint32_t(f.height());
        img.pass = snap->pass;
        img.spp = snap->spp;
      }
    } catch (const std::exception& e) {
      err = e.what();
    }
    loop_.post([this, conn, img = std::move(img), err] {
      Connection* c = find(conn);
      if (!c) return;
      if (!err.empty()) {
        log_.error("job {}: fetch failed: {}", img.job, err);
        reply_error(*c, img.id, ErrorCode::internal, "fetch: " + err);
      } else {
        c->send(protocol::encode(img));
        dirty_.insert(conn);
      }
      flush_dirty();
    });
  });
}

}  // namespace omega::daemon
