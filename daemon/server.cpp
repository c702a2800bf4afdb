// Server lifecycle and socket I/O. Everything here runs on the loop thread unless noted.
#include "daemon/server.h"

#include <sys/epoll.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <filesystem>

#include "daemon/sd_notify.h"
#include "integrator/render_session.h"

namespace omega::daemon {

namespace fs = std::filesystem;

Server::Server(std::string config_path, std::function<void(Config&)> overrides, Log& log)
    : config_path_(std::move(config_path)), overrides_(std::move(overrides)), log_(log) {}

Server::~Server() {
  // Stop every render at the next tile boundary; the workers write their last checkpoints.
  for (auto& [id, a] : active_) a.worker->request_stop(StopKind::now);
  for (auto& [id, a] : active_) a.worker->join();
}

JobPaths Server::paths(std::uint64_t job) const { return JobPaths{cfg_.state_dir + "/jobs/" + std::to_string(job)}; }

void Server::apply_config(const Config& c) {
  cfg_ = c;
  log_.set_level(c.log_level);
  tbb_limit_.reset();  // one global_control at a time
  const int threads = resolve_threads(c.threads);
  tbb_limit_ = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                     static_cast<std::size_t>(2 * threads * std::max(1, c.max_running)));
  share_.set_slots(threads);
}

void Server::start() {
  Config c = load_config(config_path_);
  if (overrides_) overrides_(c);
  validate_config(c);
  apply_config(c);

  fs::create_directories(cfg_.state_dir + "/jobs");
  fs::create_directories(cfg_.state_dir + "/staging");
  store_ = std::make_unique<JobStore>(cfg_.state_dir + "/jobs.sqlite");
  assets_ = std::make_unique<AssetCache>(cfg_.state_dir + "/assets");
  recover_jobs();
  if (!cfg_.tls_cert.empty()) tls_ = std::make_unique<TlsContext>(cfg_.tls_cert, cfg_.tls_key);
  open_listeners();

  loop_.set_error_handler([this](const std::exception& e) {
    log_.error("loop: {}; carrying on (the request or event that hit it was not completed)", e.what());
  });
  loop_.add(signals_.fd(), EPOLLIN, [this](std::uint32_t) { on_signal(); });
  if (double wd = watchdog_interval_s(); wd > 0) {
    log_.info("systemd watchdog: pinging every {:.1f} s", wd);
    loop_.add_timer(wd, [this, wd] { watchdog_tick(wd); });
  }
  loop_.add_timer(1.0, [this] { sweep_timeouts(); });
  std::string where;
  for (const auto& l : listeners_) where += (where.empty() ? "" : ", ") + l.text();
  log_.info("omegad ready: listening on {}{}; state in {}; {} render threads, {} job(s) at once", where,
            tls_ ? " (TCP over TLS)" : "", cfg_.state_dir, resolve_threads(cfg_.threads), cfg_.max_running);
  notify_ready("listening on " + where);
  reschedule();
}

namespace {
std::string refuse_open_tcp(const std::string& where) {
  return "refusing to listen on " + where +
         ": it is not a loopback address and TCP authentication is not configured (add tcp_users to the config, "
         "see docs/security.md)";
}
}  // namespace

void Server::open_listeners() {
  std::vector<int> fds = activated_sockets();
  for (int fd : fds) listeners_.push_back(Listener::adopt(fd));
  if (fds.empty()) {
    std::vector<std::string> addrs = cfg_.listen;
    if (addrs.empty()) addrs.push_back("unix:/run/omega/omegad.sock");
    for (const auto& a : addrs) {
      ListenAddress la;
      try {
        la = parse_listen_address(a);
      } catch (const std::invalid_argument& e) {
        throw std::runtime_error(e.what());
      }
      if (la.kind == ListenAddress::Kind::tcp && !la.loopback && cfg_.tcp_users.empty())
        throw std::runtime_error(refuse_open_tcp(la.text()));  // before binding it at all
      if (la.kind == ListenAddress::Kind::unix_socket) fs::create_directories(fs::path(la.path).parent_path());
      listeners_.emplace_back(la);
    }
  }
  for (const auto& l : listeners_) {
    if (l.unix_socket()) continue;
    if (!l.loopback() && cfg_.tcp_users.empty())
      throw std::runtime_error(refuse_open_tcp(l.text()));
    if (cfg_.tcp_users.empty())
      log_.warn("{}: TCP without authentication (no tcp_users): every local user acts as 'tcp'", l.text());
  }
  for (std::size_t i = 0; i < listeners_.size(); ++i)
    loop_.add(listeners_[i].fd(), EPOLLIN, [this, i](std::uint32_t) { on_accept(i); });
}

void Server::recover_jobs() {
  std::set<std::string> known;
  for (const JobRecord& r : store_->all()) {
    known.insert(std::to_string(r.id));
    if (r.state == protocol::JobState::running) {
      // It was rendering when the daemon stopped or crashed: it resumes from its checkpoint.
      store_->set_state(r.id, protocol::JobState::queued);
      log_.info("job {}: was running at the last stop; queued to resume from its checkpoint", r.id);
    }
  }
  // Directories of submits that never committed, and half-staged submits.
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(cfg_.state_dir + "/jobs", ec))
    if (!known.count(e.path().filename().string())) fs::remove_all(e.path(), ec);
  for (const auto& e : fs::directory_iterator(cfg_.state_dir + "/staging", ec)) fs::remove_all(e.path(), ec);
  // Worker jobs: units that were out when the daemon stopped are handed out again; the done ones
  // are folded again from their files (server_workers.cpp).
  store_->requeue_running_units();
  for (const JobRecord& r : store_->all()) {
    if (r.workers == 0 || protocol::is_terminal(r.state)) continue;
    try {
      load_work_job(r);
    } catch (const std::exception& e) {
      log_.error("job {}: cannot recover its work units: {}", r.id, e.what());
    }
  }
}

int Server::run() {
  loop_.run();
  return exit_code_;
}

Connection* Server::find(std::uint64_t id) {
  auto it = conns_.find(id);
  return it == conns_.end() ? nullptr : it->second.get();
}

void Server::send_frame(std::uint64_t conn, const protocol::Frame& f) {
  if (Connection* c = find(conn)) {
    c->send(f);
    dirty_.insert(conn);
  }
}

void Server::send_coalesced(std::uint64_t conn, const CoalesceKey& key, const std::string& header,
                            std::shared_ptr<const std::string> payload) {
  if (Connection* c = find(conn)) {
    c->send_coalesced(key, header, std::move(payload));
    dirty_.insert(conn);
  }
}

void Server::on_accept(std::size_t li) {
  for (;;) {
    Peer peer;
    int fd = listeners_[li].accept_one(peer);
    if (fd < 0) break;
    if (conns_.size() >= static_cast<std::size_t>(cfg_.max_connections)) {
      log_.warn("refusing connection from {}: {} connections open (max_connections)", peer.name, conns_.size());
      ::close(fd);
      continue;
    }
    protocol::DecoderLimits limits;
    limits.max_header_bytes = static_cast<std::uint32_t>(cfg_.max_header_bytes);
    limits.set_payload_limit(protocol::MessageType::submit, cfg_.max_submit_bytes);
    limits.set_payload_limit(protocol::MessageType::asset, cfg_.max_asset_bytes);
    std::uint64_t id = next_conn_++;
    SSL* ssl = nullptr;
    if (tls_ && !peer.unix_socket) {
      try {
        ssl = tls_->wrap(fd);
      } catch (const std::exception& e) {
        log_.error("connection from {}: {}", peer.name, e.what());
        ::close(fd);
        continue;
      }
    }
    auto conn = std::make_unique<Connection>(fd, id, peer, limits, cfg_.output_buffer_bytes, ssl);
    log_.debug("connection {} from {}", id, peer.name);
    conns_.emplace(id, std::move(conn));
    loop_.add(fd, EPOLLIN | EPOLLRDHUP, [this, id](std::uint32_t ev) { on_connection_event(id, ev); });
  }
}

void Server::on_connection_event(std::uint64_t id, std::uint32_t events) {
  Connection* c = find(id);
  if (!c) return;
  if (events & (EPOLLIN | EPOLLRDHUP | EPOLLHUP | EPOLLERR)) {
    std::vector<protocol::DecodedFrame> frames;
    Connection::ReadStatus st = c->read_frames(frames);
    for (auto& f : frames) {
      if (c->dead || c->closing) break;
      handle_frame(*c, f);
    }
    if (c->framing_error() && !c->dead && !c->closing) {
      const auto& e = *c->framing_error();
      std::string what = std::string(protocol::to_string(e.code)) + (e.message.empty() ? "" : ": " + e.message);
      if (e.code == protocol::FrameError::truncated) {
        log_.warn("connection {} ({}): stream ended inside a frame ({})", id, c->peer().name, what);
        c->dead = true;
      } else {
        log_.warn("connection {} ({}): bad frame: {}; closing it", id, c->peer().name, what);
        reply_error(*c, 0, protocol::ErrorCode::bad_frame, what);
        c->closing = true;
      }
    }
    if (st == Connection::ReadStatus::error) {
      if (!c->dead && !c->tls_error().empty())
        log_.warn("connection {} ({}): TLS failed: {}; closing", id, c->peer().name, c->tls_error());
      else if (!c->dead)
        log_.info("connection {} ({}): read error; closing", id, c->peer().name);
      c->dead = true;
    } else if (st == Connection::ReadStatus::eof && !c->dead) {
      log_.debug("connection {} ({}): peer closed", id, c->peer().name);
      c->closing = true;
    }
  }
  dirty_.insert(id);
  flush_dirty();
}

void Server::finish_io(Connection& c) {
  if (!c.dead && c.over_limit()) {
    log_.warn("connection {} ({}): output buffer over its limit ({} bytes queued, output_buffer_bytes {}): the "
              "client is not reading; closing it",
              c.id(), c.peer().name, c.output().owned_bytes(), cfg_.output_buffer_bytes);
    c.dead = true;
  }
  if (!c.dead && !c.flush()) {
    if (!c.tls_error().empty())
      log_.warn("connection {} ({}): TLS failed: {}; closing", c.id(), c.peer().name, c.tls_error());
    else
      log_.info("connection {} ({}): write failed (peer gone); closing", c.id(), c.peer().name);
    c.dead = true;
  }
  if (!c.dead && c.closing && !c.wants_write()) c.dead = true;
  if (c.dead) {
    close_connection(c.id(), "");
    return;
  }
  bool want = c.wants_write();
  if (want != c.write_armed) {
    loop_.modify(c.fd(), EPOLLIN | EPOLLRDHUP | (want ? EPOLLOUT : 0u));
    c.write_armed = want;
  }
}

void Server::flush_dirty() {
  while (!dirty_.empty()) {
    std::uint64_t id = *dirty_.begin();
    dirty_.erase(dirty_.begin());
    if (Connection* c = find(id)) finish_io(*c);
  }
}

void Server::close_connection(std::uint64_t id, const std::string& why) {
  auto it = conns_.find(id);
  if (it == conns_.end()) return;
  if (!why.empty()) log_.info("connection {} ({}): {}", id, it->second->peer().name, why);
  std::vector<std::uint64_t> jobs;
  publisher_.drop_connection(id);
  for (auto& [job, a] : active_) jobs.push_back(job);
  for (auto& [sid, p] : it->second->pending)
    if (!p.validating) log_.info("connection {}: submit {} abandoned before its assets arrived", id, sid);
  release_worker_units(*it->second);  // its unfinished units go to other workers
  const bool was_worker = it->second->worker.has_value();
  loop_.remove(it->second->fd());
  conns_.erase(it);
  dirty_.erase(id);
  for (auto job : jobs) update_watched(job);
  if (was_worker) dispatch_work();
}

void Server::on_signal() {
  while (int sig = signals_.read_signal()) {
    if (sig == SIGHUP) {
      reload();
    } else if (phase_ == Phase::serving) {
      begin_drain(sig == SIGTERM ? "SIGTERM" : "SIGINT");
    } else {
      log_.warn("second {}: exiting now; running jobs resume from their last checkpoint", sig == SIGTERM ? "SIGTERM" : "SIGINT");
      for (auto& [id, a] : active_) a.worker->request_stop(StopKind::now);
      phase_ = Phase::stopped;
      loop_.stop();
    }
  }
}

void Server::reload() {
  notify_reloading();
  try {
    Config c = load_config(config_path_);
    if (overrides_) overrides_(c);
    validate_config(c);
    if (c.state_dir != cfg_.state_dir) log_.warn("config reload: state_dir changes take effect at the next start");
    if (c.listen != cfg_.listen) log_.warn("config reload: listen changes take effect at the next start");
    c.state_dir = cfg_.state_dir;
    c.listen = cfg_.listen;
    apply_config(c);
    log_.info("config reloaded from {}: {} render threads, {} job(s) at once", config_path_.empty() ? "(defaults)" : config_path_,
              resolve_threads(cfg_.threads), cfg_.max_running);
  } catch (const std::exception& e) {
    log_.error("config reload failed, keeping the old config: {}", e.what());
  }
  notify_ready("config reloaded");
  reschedule();
}

void Server::begin_drain(const char* why) {
  phase_ = Phase::draining;
  notify_stopping();
  log_.info("{}: draining: no new jobs; {} running job(s) stop at their next pass boundary (deadline {} s)", why,
            active_.size(), cfg_.drain_timeout_s);
  for (auto& l : listeners_) loop_.remove(l.fd());
  listeners_.clear();
  for (auto& [id, a] : active_) a.worker->request_stop(StopKind::drain);
  loop_.add_timer(cfg_.drain_timeout_s, [this] {
    if (active_.empty()) return;
    log_.warn("drain deadline passed: aborting {} job(s) at the next tile; they resume from their last checkpoint",
              active_.size());
    for (auto& [id, a] : active_) a.worker->request_stop(StopKind::now);
  });
  maybe_finish_shutdown();
}

void Server::maybe_finish_shutdown() {
  if (phase_ != Phase::draining || !active_.empty()) return;
  if (!unrecorded_.empty())
    log_.warn("{} job end(s) could not be recorded in the job store; those jobs are queued again at the next start "
              "and finish from their final checkpoint",
              unrecorded_.size());
  // Give clients what is queued for them (best effort, without blocking), then stop.
  for (auto& [id, c] : conns_) c->flush();
  log_.info("drained; exiting");
  phase_ = Phase::stopped;
  loop_.stop();
}

void Server::sweep_timeouts() {
  dispatch_work();  // units a store error kept back are retried here
  poll_slurm();     // executor slurm: at most every slurm.poll_s
  const auto now = std::chrono::steady_clock::now();
  auto secs = [&](std::chrono::steady_clock::time_point t) { return std::chrono::duration<double>(now - t).count(); };
  std::vector<std::uint64_t> cut;
  for (auto& [id, c] : conns_) {
    if (c->dead) continue;
    if (auto since = c->partial_since(); since && cfg_.frame_timeout_s > 0 && secs(*since) > cfg_.frame_timeout_s) {
      log_.warn("connection {} ({}): no byte for {:.0f} s inside a frame (frame_timeout_s); closing", id,
                c->peer().name, secs(*since));
      reply_error(*c, 0, protocol::ErrorCode::bad_frame, "timeout: the frame was not completed in time");
      cut.push_back(id);
    } else if (!c->authenticated && !c->closing && secs(c->opened_at()) > cfg_.handshake_timeout_s) {
      log_.warn("connection {} ({}): handshake not completed within {} s (handshake_timeout_s); closing", id,
                c->peer().name, cfg_.handshake_timeout_s);
      reply_error(*c, 0, protocol::ErrorCode::auth_required, "timeout: hello/auth not completed in time");
      cut.push_back(id);
    }
  }
  for (auto id : cut) {
    Connection* c = find(id);
    c->flush();  // best effort: the error frame, without waiting for a peer that may not read
    c->dead = true;
    dirty_.insert(id);
  }
  flush_dirty();
  for (auto it = auth_failures_.begin(); it != auth_failures_.end();) {
    auto next = std::next(it);
    recent_auth_failures(it->first, now);  // drops the address once its last failure is a minute old
    it = next;
  }
  retry_store();
  flush_dirty();
  loop_.add_timer(1.0, [this] { sweep_timeouts(); });
}

void Server::watchdog_tick(double interval) {
  notify_watchdog();
  loop_.add_timer(interval, [this, interval] { watchdog_tick(interval); });
}

}  // namespace omega::daemon
