#pragma once
// The durable queue: one SQLite database (WAL, synchronous=FULL) under the state dir. Every
// accepted job is a row; a job is durable once insert() returns. Loop thread only (the
// connection is not shared).
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "protocol/messages.h"

struct sqlite3;

namespace omega::daemon {

struct JobRecord {
  std::uint64_t id = 0;
  std::string name;
  std::string owner;
  std::int64_t priority = 0;
  protocol::JobState state = protocol::JobState::queued;
  protocol::Halt halt;
  std::uint64_t seed = 0;
  std::string integrator;  // empty: the scene's
  std::string sampler;     // empty: the scene's
  protocol::ProgressInfo progress;
  std::string message;  // why it failed
  std::uint32_t workers = 0;   // > 0: rendered by `omega worker`s in units (omegad starts this many under Slurm)
  std::uint64_t unit_spp = 0;  // samples per unit; 0: sized by the daemon (config unit_seconds)

  protocol::JobInfo info() const;
};

// A work unit of a worker job: samples [begin, end) of every pixel. queued -> running (owner:
// the worker session) -> done (its part is on disk under the job's units/ folder). A running
// unit whose worker goes away is queued again; a done unit never changes.
enum class UnitState { queued, running, done };
const char* to_string(UnitState s);
struct UnitRecord {
  std::uint64_t job = 0;
  std::uint64_t unit = 0;
  std::uint64_t begin = 0, end = 0;
  UnitState state = UnitState::queued;
  std::string owner;  // worker session name while running
  double time_s = 0;  // render time of a done unit
};

class JobStore {
 public:
  // Opens or creates PATH. Throws std::runtime_error naming the path and SQLite's message.
  explicit JobStore(const std::string& path);
  ~JobStore();
  JobStore(const JobStore&) = delete;
  JobStore& operator=(const JobStore&) = delete;

  // Inserts r (its id is ignored) in a transaction. before_commit(id) runs inside it (e.g. to
  // move the job's files into place); if it throws, the insert is rolled back and the exception
  // passes on. Returns the new id.
  std::uint64_t insert(const JobRecord& r, const std::function<void(std::uint64_t)>& before_commit);
  std::optional<JobRecord> get(std::uint64_t id);
  std::vector<JobRecord> all();  // by id
  // Queued jobs in run order: priority (high first), then FIFO.
  std::vector<JobRecord> queued();
  std::size_t count_unfinished();
  std::size_t count_unfinished(const std::string& owner);  // max_jobs_per_owner

  // Every write below is one statement (atomic). A write that cannot get the database within the
  // busy timeout (another process holds it locked) or fails throws std::runtime_error with
  // SQLite's message ("database is locked", "disk I/O error"): the caller decides whether to
  // retry (Server::retry_store) or to refuse the request with an error frame.
  void set_state(std::uint64_t id, protocol::JobState s, const std::string& message = {});
  // A finished or stopped job's state, message and progress in one statement.
  void set_outcome(std::uint64_t id, protocol::JobState s, const protocol::ProgressInfo& p,
                   const std::string& message = {});
  void set_priority(std::uint64_t id, std::int64_t p);
  void set_progress(std::uint64_t id, const protocol::ProgressInfo& p);
  void remove(std::uint64_t id);  // and its units

  // Work units (loop thread). units() by unit number; put_unit inserts or replaces one row.
  std::vector<UnitRecord> units(std::uint64_t job);
  void put_unit(const UnitRecord& u);
  // At start-up: units that were running when the daemon died go back to the queue.
  void requeue_running_units();

  // Slurm jobs of worker jobs (executor slurm): recorded once sbatch returns their id, marked
  // ended when squeue no longer lists them or omegad scancels them.
  struct SlurmRecord {
    std::uint64_t job = 0;
    std::string slurm_id;
    int tasks = 0;
  };
  void add_slurm_job(std::uint64_t job, const std::string& slurm_id, int tasks);
  void end_slurm_job(const std::string& slurm_id);
  std::vector<SlurmRecord> active_slurm_jobs();  // not ended, by slurm id
  std::size_t count_slurm_jobs(std::uint64_t job);  // ever submitted for the job

  // How long a statement waits for a lock held elsewhere before failing (default 5000 ms).
  // While it waits, the loop thread is blocked; retries use a short one (QuickBusy).
  void set_busy_timeout_ms(int ms);
  class QuickBusy {  // scope guard: a short busy timeout, then the default again
   public:
    explicit QuickBusy(JobStore& s, int ms = 100) : s_(s) { s_.set_busy_timeout_ms(ms); }
    ~QuickBusy() { s_.set_busy_timeout_ms(kDefaultBusyMs); }
    QuickBusy(const QuickBusy&) = delete;
    QuickBusy& operator=(const QuickBusy&) = delete;

   private:
    JobStore& s_;
  };
  static constexpr int kDefaultBusyMs = 5000;

 private:
  void exec(const char* sql);
  std::vector<JobRecord> select(const std::string& where_order, std::optional<std::uint64_t> id = {});
  sqlite3* db_ = nullptr;
  std::string path_;
};

std::optional<protocol::JobState> job_state_from_string(std::string_view s);

}  // namespace omega::daemon
