#include "daemon/job_store.h"

#include <sqlite3.h>

#include <set>
#include <stdexcept>

namespace omega::daemon {

namespace {

class Stmt {
 public:
  Stmt(sqlite3* db, const std::string& sql, const std::string& path) : db_(db) {
    if (sqlite3_prepare_v2(db, sql.c_str(), -1, &s_, nullptr) != SQLITE_OK)
      throw std::runtime_error(path + ": " + sqlite3_errmsg(db) + " in: " + sql);
  }
  ~Stmt() { sqlite3_finalize(s_); }
  Stmt& bind(int i, std::int64_t v) { sqlite3_bind_int64(s_, i, v); return *this; }
  Stmt& bind(int i, const std::string& v) { sqlite3_bind_text(s_, i, v.c_str(), int(v.size()), SQLITE_TRANSIENT); return *this; }
  Stmt& bind(int i, double v) { sqlite3_bind_double(s_, i, v); return *this; }
  Stmt& bind_null(int i) { sqlite3_bind_null(s_, i); return *this; }
  template <class T>
  Stmt& bind_opt(int i, const std::optional<T>& v) {
    if (v) return bind(i, static_cast<std::conditional_t<std::is_integral_v<T>, std::int64_t, double>>(*v));
    return bind_null(i);
  }
  bool step() {
    int rc = sqlite3_step(s_);
    if (rc == SQLITE_ROW) return true;
    if (rc == SQLITE_DONE) return false;
    throw std::runtime_error(std::string("job store: ") + sqlite3_errmsg(db_));
  }
  sqlite3_stmt* get() { return s_; }

 private:
  sqlite3* db_;
  sqlite3_stmt* s_ = nullptr;
};

const char* kColumns =
    "id, name, owner, priority, state, halt_spp, halt_time, halt_error, seed, integrator, "
    "pass, spp, elapsed_s, rel_error, samples_per_s, message, sampler, workers, unit_spp";

std::optional<std::int64_t> opt_int(sqlite3_stmt* s, int i) {
  if (sqlite3_column_type(s, i) == SQLITE_NULL) return std::nullopt;
  return sqlite3_column_int64(s, i);
}
std::optional<double> opt_double(sqlite3_stmt* s, int i) {
  if (sqlite3_column_type(s, i) == SQLITE_NULL) return std::nullopt;
  return sqlite3_column_double(s, i);
}
std::string text(sqlite3_stmt* s, int i) {
  const unsigned char* t = sqlite3_column_text(s, i);
  return t ? std::string(reinterpret_cast<const char*>(t), std::size_t(sqlite3_column_bytes(s, i))) : std::string();
}

}  // namespace

std::optional<protocol::JobState> job_state_from_string(std::string_view s) {
  using protocol::JobState;
  for (JobState st : {JobState::queued, JobState::running, JobState::paused, JobState::done, JobState::failed,
                      JobState::cancelled})
    if (protocol::to_string(st) == s) return st;
  return std::nullopt;
}

protocol::JobInfo JobRecord::info() const {
  protocol::JobInfo i;
  i.job = id;
  i.name = name;
  i.state = state;
  i.priority = priority;
  i.owner = owner;
  i.halt = halt;
  i.progress = progress;
  return i;
}

JobStore::JobStore(const std::string& path) : path_(path) {
  if (sqlite3_open_v2(path.c_str(), &db_, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_NOMUTEX, nullptr) !=
      SQLITE_OK) {
    std::string msg = db_ ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close(db_);
    db_ = nullptr;
    throw std::runtime_error(path + ": " + msg);
  }
  sqlite3_busy_timeout(db_, kDefaultBusyMs);
  exec("PRAGMA journal_mode=WAL");
  exec("PRAGMA synchronous=FULL");
  exec(
      "CREATE TABLE IF NOT EXISTS jobs ("
      " id INTEGER PRIMARY KEY AUTOINCREMENT,"
      " name TEXT NOT NULL, owner TEXT NOT NULL, priority INTEGER NOT NULL, state TEXT NOT NULL,"
      " halt_spp INTEGER, halt_time REAL, halt_error REAL, seed INTEGER NOT NULL, integrator TEXT NOT NULL,"
      " pass INTEGER NOT NULL DEFAULT 0, spp INTEGER NOT NULL DEFAULT 0, elapsed_s REAL NOT NULL DEFAULT 0,"
      " rel_error REAL, samples_per_s REAL NOT NULL DEFAULT 0, message TEXT NOT NULL DEFAULT '',"
      " created TEXT NOT NULL DEFAULT (datetime('now')))");
  exec("CREATE INDEX IF NOT EXISTS jobs_queue ON jobs(state, priority DESC, id)");
  // Stores made before a column existed lack it: the sampler override (empty: the scene's) and
  // the work units (0 workers: a local job).
  std::set<std::string> columns;
  {
    Stmt info(db_, "SELECT name FROM pragma_table_info('jobs')", path_);
    while (info.step()) columns.insert(text(info.get(), 0));
  }
  if (!columns.count("sampler")) exec("ALTER TABLE jobs ADD COLUMN sampler TEXT NOT NULL DEFAULT ''");
  if (!columns.count("workers")) exec("ALTER TABLE jobs ADD COLUMN workers INTEGER NOT NULL DEFAULT 0");
  if (!columns.count("unit_spp")) exec("ALTER TABLE jobs ADD COLUMN unit_spp INTEGER NOT NULL DEFAULT 0");
  // A job's work units (docs/farm.md "Workers"): sample ranges [begin, end_), their state and the
  // worker session that holds a running one.
  exec(
      "CREATE TABLE IF NOT EXISTS units ("
      " job INTEGER NOT NULL, unit INTEGER NOT NULL, begin INTEGER NOT NULL, end_ INTEGER NOT NULL,"
      " state TEXT NOT NULL, owner TEXT NOT NULL DEFAULT '', time_s REAL NOT NULL DEFAULT 0,"
      " PRIMARY KEY (job, unit))");
  exec(
      "CREATE TABLE IF NOT EXISTS slurm_jobs ("
      " slurm_id TEXT PRIMARY KEY, job INTEGER NOT NULL, tasks INTEGER NOT NULL, state TEXT NOT NULL)");
}

JobStore::~JobStore() { sqlite3_close(db_); }

void JobStore::exec(const char* sql) {
  char* err = nullptr;
  if (sqlite3_exec(db_, sql, nullptr, nullptr, &err) != SQLITE_OK) {
    std::string msg = err ? err : "?";
    sqlite3_free(err);
    throw std::runtime_error(path_ + ": " + msg);
  }
}

std::uint64_t JobStore::insert(const JobRecord& r, const std::function<void(std::uint64_t)>& before_commit) {
  exec("BEGIN IMMEDIATE");
  try {
    Stmt s(db_,
           "INSERT INTO jobs (name, owner, priority, state, halt_spp, halt_time, halt_error, seed, integrator, sampler,"
           " workers, unit_spp) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
           path_);
    s.bind(1, r.name).bind(2, r.owner).bind(3, r.priority).bind(4, std::string(protocol::to_string(r.state)));
    s.bind_opt(5, r.halt.spp).bind_opt(6, r.halt.time_s).bind_opt(7, r.halt.target_error);
    s.bind(8, static_cast<std::int64_t>(r.seed)).bind(9, r.integrator).bind(10, r.sampler);
    s.bind(11, static_cast<std::int64_t>(r.workers)).bind(12, static_cast<std::int64_t>(r.unit_spp));
    s.step();
    auto id = static_cast<std::uint64_t>(sqlite3_last_insert_rowid(db_));
    if (before_commit) before_commit(id);
    exec("COMMIT");
    return id;
  } catch (...) {
    sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
    throw;
  }
}

std::vector<JobRecord> JobStore::select(const std::string& where_order, std::optional<std::uint64_t> id) {
  Stmt s(db_, std::string("SELECT ") + kColumns + " FROM jobs " + where_order, path_);
  if (id) s.bind(1, static_cast<std::int64_t>(*id));
  std::vector<JobRecord> out;
  while (s.step()) {
    sqlite3_stmt* q = s.get();
    JobRecord r;
    r.id = static_cast<std::uint64_t>(sqlite3_column_int64(q, 0));
    r.name = text(q, 1);
    r.owner = text(q, 2);
    r.priority = sqlite3_column_int64(q, 3);
    r.state = job_state_from_string(text(q, 4)).value_or(protocol::JobState::failed);
    if (auto v = opt_int(q, 5)) r.halt.spp = static_cast<std::uint64_t>(*v);
    r.halt.time_s = opt_double(q, 6);
    r.halt.target_error = opt_double(q, 7);
    r.seed = static_cast<std::uint64_t>(sqlite3_column_int64(q, 8));
    r.integrator = text(q, 9);
    r.progress.pass = static_cast<std::uint64_t>(sqlite3_column_int64(q, 10));
    r.progress.spp = static_cast<std::uint64_t>(sqlite3_column_int64(q, 11));
    r.progress.elapsed_s = sqlite3_column_double(q, 12);
    r.progress.rel_error = opt_double(q, 13);
    r.progress.samples_per_s = sqlite3_column_double(q, 14);
    r.message = text(q, 15);
    r.sampler = text(q, 16);
    r.workers = static_cast<std::uint32_t>(sqlite3_column_int64(q, 17));
    r.unit_spp = static_cast<std::uint64_t>(sqlite3_column_int64(q, 18));
    out.push_back(std::move(r));
  }
  return out;
}

std::optional<JobRecord> JobStore::get(std::uint64_t id) {
  auto v = select("WHERE id = ?", id);
  if (v.empty()) return std::nullopt;
  return v.front();
}

std::vector<JobRecord> JobStore::all() { return select("ORDER BY id"); }

std::vector<JobRecord> JobStore::queued() { return select("WHERE state = 'queued' ORDER BY priority DESC, id"); }

std::size_t JobStore::count_unfinished() {
  Stmt s(db_, "SELECT count(*) FROM jobs WHERE state IN ('queued', 'running', 'paused')", path_);
  s.step();
  return static_cast<std::size_t>(sqlite3_column_int64(s.get(), 0));
}

std::size_t JobStore::count_unfinished(const std::string& owner) {
  Stmt s(db_, "SELECT count(*) FROM jobs WHERE owner = ? AND state IN ('queued', 'running', 'paused')", path_);
  s.bind(1, owner);
  s.step();
  return static_cast<std::size_t>(sqlite3_column_int64(s.get(), 0));
}

void JobStore::set_state(std::uint64_t id, protocol::JobState st, const std::string& message) {
  Stmt s(db_, "UPDATE jobs SET state = ?, message = ? WHERE id = ?", path_);
  s.bind(1, std::string(protocol::to_string(st))).bind(2, message).bind(3, static_cast<std::int64_t>(id));
  s.step();
}

void JobStore::set_outcome(std::uint64_t id, protocol::JobState st, const protocol::ProgressInfo& p,
                           const std::string& message) {
  Stmt s(db_,
         "UPDATE jobs SET state = ?, message = ?, pass = ?, spp = ?, elapsed_s = ?, rel_error = ?, samples_per_s = ?"
         " WHERE id = ?",
         path_);
  s.bind(1, std::string(protocol::to_string(st))).bind(2, message);
  s.bind(3, static_cast<std::int64_t>(p.pass)).bind(4, static_cast<std::int64_t>(p.spp)).bind(5, p.elapsed_s);
  s.bind_opt(6, p.rel_error).bind(7, p.samples_per_s).bind(8, static_cast<std::int64_t>(id));
  s.step();
}

void JobStore::set_busy_timeout_ms(int ms) { sqlite3_busy_timeout(db_, ms); }

void JobStore::set_priority(std::uint64_t id, std::int64_t p) {
  Stmt s(db_, "UPDATE jobs SET priority = ? WHERE id = ?", path_);
  s.bind(1, p).bind(2, static_cast<std::int64_t>(id));
  s.step();
}

void JobStore::set_progress(std::uint64_t id, const protocol::ProgressInfo& p) {
  Stmt s(db_, "UPDATE jobs SET pass = ?, spp = ?, elapsed_s = ?, rel_error = ?, samples_per_s = ? WHERE id = ?", path_);
  s.bind(1, static_cast<std::int64_t>(p.pass)).bind(2, static_cast<std::int64_t>(p.spp)).bind(3, p.elapsed_s);
  s.bind_opt(4, p.rel_error).bind(5, p.samples_per_s).bind(6, static_cast<std::int64_t>(id));
  s.step();
}

void JobStore::remove(std::uint64_t id) {
  Stmt s(db_, "DELETE FROM jobs WHERE id = ?", path_);
  s.bind(1, static_cast<std::int64_t>(id));
  s.step();
  Stmt u(db_, "DELETE FROM units WHERE job = ?", path_);
  u.bind(1, static_cast<std::int64_t>(id));
  u.step();
}

const char* to_string(UnitState s) {
  switch (s) {
    case UnitState::queued: return "queued";
    case UnitState::running: return "running";
    case UnitState::done: return "done";
  }
  return "queued";
}

std::vector<UnitRecord> JobStore::units(std::uint64_t job) {
  Stmt s(db_, "SELECT unit, begin, end_, state, owner, time_s FROM units WHERE job = ? ORDER BY unit", path_);
  s.bind(1, static_cast<std::int64_t>(job));
  std::vector<UnitRecord> out;
  while (s.step()) {
    sqlite3_stmt* q = s.get();
    UnitRecord u;
    u.job = job;
    u.unit = static_cast<std::uint64_t>(sqlite3_column_int64(q, 0));
    u.begin = static_cast<std::uint64_t>(sqlite3_column_int64(q, 1));
    u.end = static_cast<std::uint64_t>(sqlite3_column_int64(q, 2));
    const std::string st = text(q, 3);
    u.state = st == "done" ? UnitState::done : st == "running" ? UnitState::running : UnitState::queued;
    u.owner = text(q, 4);
    u.time_s = sqlite3_column_double(q, 5);
    out.push_back(std::move(u));
  }
  return out;
}

void JobStore::put_unit(const UnitRecord& u) {
  Stmt s(db_, "INSERT OR REPLACE INTO units (job, unit, begin, end_, state, owner, time_s) VALUES (?, ?, ?, ?, ?, ?, ?)",
         path_);
  s.bind(1, static_cast<std::int64_t>(u.job)).bind(2, static_cast<std::int64_t>(u.unit));
  s.bind(3, static_cast<std::int64_t>(u.begin)).bind(4, static_cast<std::int64_t>(u.end));
  s.bind(5, std::string(to_string(u.state))).bind(6, u.owner).bind(7, u.time_s);
  s.step();
}

void JobStore::add_slurm_job(std::uint64_t job, const std::string& slurm_id, int tasks) {
  Stmt s(db_, "INSERT OR REPLACE INTO slurm_jobs (slurm_id, job, tasks, state) VALUES (?, ?, ?, 'active')", path_);
  s.bind(1, slurm_id).bind(2, static_cast<std::int64_t>(job)).bind(3, static_cast<std::int64_t>(tasks));
  s.step();
}

void JobStore::end_slurm_job(const std::string& slurm_id) {
  Stmt s(db_, "UPDATE slurm_jobs SET state = 'ended' WHERE slurm_id = ?", path_);
  s.bind(1, slurm_id);
  s.step();
}

std::vector<JobStore::SlurmRecord> JobStore::active_slurm_jobs() {
  Stmt s(db_, "SELECT job, slurm_id, tasks FROM slurm_jobs WHERE state = 'active' ORDER BY slurm_id", path_);
  std::vector<SlurmRecord> out;
  while (s.step())
    out.push_back({static_cast<std::uint64_t>(sqlite3_column_int64(s.get(), 0)), text(s.get(), 1),
                   static_cast<int>(sqlite3_column_int64(s.get(), 2))});
  return out;
}

std::size_t JobStore::count_slurm_jobs(std::uint64_t job) {
  Stmt s(db_, "SELECT count(*) FROM slurm_jobs WHERE job = ?", path_);
  s.bind(1, static_cast<std::int64_t>(job));
  s.step();
  return static_cast<std::size_t>(sqlite3_column_int64(s.get(), 0));
}

void JobStore::requeue_running_units() { exec("UPDATE units SET state = 'queued', owner = '' WHERE state = 'running'"); }

}  // namespace omega::daemon
