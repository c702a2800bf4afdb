#pragma once
// The daemon: everything hangs off one Server object (no global state). The loop thread runs
// run(); it owns the sockets, the job store and the tile publisher. Render workers and the
// background thread talk to it only through EventLoop::post().
#include <tbb/global_control.h>

#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "daemon/asset_cache.h"
#include "daemon/background.h"
#include "daemon/config.h"
#include "daemon/connection.h"
#include "daemon/event_loop.h"
#include "daemon/job_store.h"
#include "daemon/listener.h"
#include "daemon/log.h"
#include "daemon/render_worker.h"
#include "daemon/signals.h"
#include "daemon/thread_share.h"
#include "daemon/tile_inbox.h"
#include "daemon/tile_publisher.h"
#include "daemon/tls.h"
#include "daemon/unit_fold.h"

namespace omega::daemon {

// The error code for a request that failed on a store error: `busy` for what passes (a lock held
// elsewhere, a full disk), `internal` otherwise. Any thread.
protocol::ErrorCode store_error_code(const std::string& what);

class Server : public FrameSink {
 public:
  // How long a streamed tile may wait for others to share its wake-up of the loop (tile_inbox.h).
  static constexpr double kTileBatchSeconds = 0.05;
  // overrides: re-applied after every (re)load of the config file (command-line flags).
  Server(std::string config_path, std::function<void(Config&)> overrides, Log& log);
  ~Server() override;
  Server(const Server&) = delete;
  Server& operator=(const Server&) = delete;

  // Main thread, before run(): loads the config, opens the state dir and the listeners (or
  // adopts systemd's), recovers jobs. Throws std::runtime_error with a message for the user.
  void start();
  // Becomes the loop thread. Returns the exit code once shut down.
  int run();

  // FrameSink (loop thread).
  void send_frame(std::uint64_t conn, const protocol::Frame& f) override;
  void send_coalesced(std::uint64_t conn, const CoalesceKey& key, const std::string& header,
                      std::shared_ptr<const std::string> payload) override;

 private:
  struct Active {
    std::unique_ptr<RenderWorker> worker;
  };
  struct Memo {  // the newest film of a job, in memory
    std::shared_ptr<const FilmSnapshot> snapshot;
    std::optional<FilmDesc> film;
  };

  // server.cpp: lifecycle and I/O (loop thread).
  void apply_config(const Config& c);
  void open_listeners();
  void recover_jobs();
  void on_accept(std::size_t listener);
  void on_connection_event(std::uint64_t id, std::uint32_t events);
  void finish_io(Connection& c);
  void close_connection(std::uint64_t id, const std::string& why);
  void flush_dirty();
  Connection* find(std::uint64_t id);
  void on_signal();
  void reload();
  void begin_drain(const char* why);
  void maybe_finish_shutdown();
  void watchdog_tick(double interval);
  void sweep_timeouts();  // every second: stalled half frames, unfinished handshakes

  // server_requests.cpp: protocol handlers (loop thread).
  void handle_frame(Connection& c, protocol::DecodedFrame& f);
  void dispatch(Connection& c, const protocol::DecodedFrame& f, protocol::Message& m);  // throws on store errors
  void reply_error(Connection& c, std::uint64_t id, protocol::ErrorCode code, const std::string& msg);
  // The job's owner, root, the daemon's own uid, or an identity in cfg_.admins.
  bool may_access(const Connection& c, const JobRecord& r) const;
  void deny(Connection& c, std::uint64_t id, std::string_view what, const JobRecord& r);
  bool tcp_auth_required(const Connection& c) const;
  void on_auth(Connection& c, const protocol::DecodedFrame& f);
  // Failed TCP authentications of one source address within the last minute (auth_fail_limit).
  // Loop thread only.
  std::size_t recent_auth_failures(const std::string& address, std::chrono::steady_clock::time_point now);
  void on_submit(Connection& c, protocol::Submit s);
  void on_asset(Connection& c, protocol::Asset a);
  void enforce_asset_cache_limit();
  void on_job_request(Connection& c, protocol::MessageType t, std::uint64_t id, std::uint64_t job,
                      std::optional<std::int64_t> priority);
  void on_subscribe(Connection& c, std::uint64_t id, std::uint64_t job);
  void on_fetch(Connection& c, std::uint64_t id, std::uint64_t job);

  // server_jobs.cpp: validation, scheduling, worker events (loop thread).
  void validate(Connection& c, std::uint64_t submit_id);
  struct Validation {
    bool ok = false;
    protocol::ErrorCode code = protocol::ErrorCode::scene_invalid;
    std::string message;
    protocol::Halt halt;
    std::string staging;
  };
  void on_validated(std::uint64_t conn, const protocol::Submit& s, Validation v);
  // Starts and preempts jobs. A store error (SQLite locked) is logged and the whole decision is
  // retried every second by retry_store(); it never leaves reschedule().
  void reschedule();
  void reschedule_now();  // throws on a store error
  void start_job(const JobRecord& r);
  void on_pass(PassUpdate u);
  void on_tile(TileUpdate t);
  void on_finish(WorkerResult r);
  // Records a finished or stopped worker's outcome in the store and tells the subscribers.
  // Throws on a store error, having changed nothing that a later call would not redo.
  void record_finish(const WorkerResult& r);
  // Every second (sweep_timeouts): outcomes the store refused, then a deferred reschedule.
  void retry_store();
  void update_watched(std::uint64_t job);
  std::shared_ptr<const FilmSnapshot> latest_snapshot(std::uint64_t job);
  JobPaths paths(std::uint64_t job) const;

  // server_workers.cpp: work units for `omega worker`s (loop thread). docs/farm.md "Workers".
  struct WorkJob {
    std::vector<UnitRecord> units;   // by unit number, as in the store
    std::uint64_t target = 0;        // samples wanted: halt spp, or max_spp for time/error halts
    std::uint64_t next_fold = 0;     // the first unit not yet handed to the fold
    std::uint64_t fold_end = 0;      // samples [0, fold_end) are handed to the fold
    bool finishing = false;          // halted: the result is being written
    double base_elapsed_s = 0;       // elapsed before this daemon process took the job up
    std::optional<std::chrono::steady_clock::time_point> started;  // first unit handed out here
    std::shared_ptr<UnitFold> fold;  // background thread only (unit_fold.h)
    std::string scene;               // the scene text, read once
    std::vector<protocol::AssetRef> assets;
    double spp_per_thread_s = 0;     // measured: samples per pixel per second and worker thread
  };
  bool is_worker_job(std::uint64_t job) const { return work_.count(job) > 0; }
  void load_work_job(const JobRecord& r);  // at accept and at start-up
  void on_work_request(Connection& c, const protocol::WorkRequest& m);
  void on_asset_request(Connection& c, const protocol::AssetRequest& m);
  void on_unit_result(Connection& c, protocol::UnitResult m);
  void on_unit_stored(std::uint64_t conn, const protocol::UnitResult& m, const std::string& error);
  // Hands units to the workers that wait for one: jobs by priority, then FIFO.
  void dispatch_work();
  bool assign_unit(Connection& c);  // true when a unit went out
  // Units of the job's running set go back to the queue; their workers get unit_stop.
  void stop_units(std::uint64_t job, const std::string& reason);
  void release_worker_units(Connection& c);  // a worker left
  // Loop thread: a running unit goes back to the queue, in the store first (a store error is
  // logged: the next start requeues what the store still calls running).
  void requeue_unit(std::uint64_t job, UnitRecord& u);
  void advance_fold(std::uint64_t job);
  void on_fold(FoldUpdate u);
  void finish_work_job(std::uint64_t job, const std::string& why);
  void on_work_done(std::uint64_t job, std::uint64_t spp, const std::string& error);
  protocol::JobInfo job_info(const JobRecord& r) const;  // with the workers of a worker job
  // Whether a connection may take work: role worker, or an identity that may act on any job.
  bool may_work(const Connection& c) const;
  std::uint64_t unit_size(const JobRecord& r, const WorkJob& w, const Connection& c) const;
  // server_slurm.cpp (executor slurm): every poll_s, squeue the workers omegad started; start
  // them for worker jobs that have work and fewer live workers than they want; scancel them
  // when a job ends, is paused or cancelled.
  void poll_slurm();
  void on_slurm_alive(const std::map<std::string, int>& alive, const std::string& error);
  void start_slurm_workers(std::uint64_t job, int count);
  void stop_slurm_workers(std::uint64_t job, const std::string& why);
  bool needs_work(std::uint64_t job) const;
  bool slurm_polling_ = false;
  std::chrono::steady_clock::time_point next_slurm_poll_{};
  std::map<std::uint64_t, int> slurm_started_;  // job -> workers started in this process
  std::set<std::uint64_t> slurm_launching_;     // jobs with an sbatch under way

  std::string config_path_;
  std::function<void(Config&)> overrides_;
  Log& log_;
  Config cfg_;
  EventLoop loop_;
  SignalFd signals_;
  // Lets each running job's arena have twice --threads (render_worker.cpp says why); share_
  // then keeps at most --threads tiles running daemon-wide, shared by priority weight.
  std::unique_ptr<tbb::global_control> tbb_limit_;
  ThreadShare share_{1};
  std::unique_ptr<JobStore> store_;
  std::unique_ptr<AssetCache> assets_;
  std::vector<Listener> listeners_;
  std::unique_ptr<TlsContext> tls_;  // set at start when tls_cert/tls_key are; TCP only
  std::map<std::uint64_t, std::unique_ptr<Connection>> conns_;
  std::set<std::uint64_t> dirty_;  // connections with output to flush at the end of this turn
  std::uint64_t next_conn_ = 1;
  std::uint64_t next_staging_ = 1;
  TilePublisher publisher_{*this};
  // The render threads' finished tiles, handed to on_tile in batches (tile_inbox.h). Before
  // active_: the workers that push into it are destroyed first.
  TileInbox tile_inbox_{loop_, kTileBatchSeconds, [this](std::vector<TileUpdate> tiles) {
                          for (TileUpdate& t : tiles) on_tile(std::move(t));
                          flush_dirty();
                        }};
  std::map<std::uint64_t, Active> active_;
  std::map<std::uint64_t, Memo> memo_;
  std::map<std::uint64_t, WorkJob> work_;  // unfinished worker jobs
  // The concurrency rule for all members above and below: the loop thread alone reads and writes
  // them (workers and the background thread only post closures to loop_), so no lock is taken.
  // Worker outcomes the store refused (e.g. "database is locked"): retried by retry_store(); the
  // job's store row still says running meanwhile.
  std::map<std::uint64_t, WorkerResult> unrecorded_;
  bool reschedule_pending_ = false;  // a reschedule() hit a store error; retry_store() redoes it
  std::chrono::steady_clock::time_point progress_backoff_until_{};  // skip progress writes until then
  // Source address -> times of its failed TCP authentications in the last minute (at most
  // auth_fail_limit of them; addresses pruned by sweep_timeouts, at most kMaxAuthFailAddresses).
  std::map<std::string, std::deque<std::chrono::steady_clock::time_point>> auth_failures_;
  static constexpr std::size_t kMaxAuthFailAddresses = 65536;
  enum class Phase { serving, draining, stopped } phase_ = Phase::serving;
  int exit_code_ = 0;
  Background background_;  // last: destroyed first, while the rest still exists
};

}  // namespace omega::daemon
