#include "daemon/job_store.h"

#include <gtest/gtest.h>

#include <sqlite3.h>

#include <filesystem>
#include <stdexcept>

namespace omega::daemon {
namespace {

struct TempDir {
  std::filesystem::path p;
  TempDir() {
    p = std::filesystem::temp_directory_path() / ("omegad-store-" + std::to_string(::getpid()) + "-" +
                                                  ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(p);
    std::filesystem::create_directories(p);
  }
  ~TempDir() { std::filesystem::remove_all(p); }
};

JobRecord rec(const char* name, std::int64_t prio) {
  JobRecord r;
  r.name = name;
  r.owner = "1000";
  r.priority = prio;
  r.halt.spp = 16;
  return r;
}

TEST(JobStore, QueueOrderIsPriorityThenFifoAndSurvivesReopening) {
  TempDir t;
  std::string db = (t.p / "jobs.sqlite").string();
  {
    JobStore s(db);
    s.insert(rec("a", 0), {});
    s.insert(rec("b", 5), {});
    s.insert(rec("c", 0), {});
    std::uint64_t d = s.insert(rec("d", 9), {});
    s.set_state(d, protocol::JobState::paused);
  }
  JobStore s(db);
  auto q = s.queued();
  ASSERT_EQ(q.size(), 3u);
  EXPECT_EQ(q[0].name, "b");
  EXPECT_EQ(q[1].name, "a");
  EXPECT_EQ(q[2].name, "c");
  EXPECT_EQ(s.get(4)->state, protocol::JobState::paused);
  EXPECT_EQ(*s.get(1)->halt.spp, 16u);
  EXPECT_EQ(s.count_unfinished(), 4u);
}

TEST(JobStore, AFailingBeforeCommitRollsTheInsertBack) {
  TempDir t;
  JobStore s((t.p / "jobs.sqlite").string());
  EXPECT_THROW(s.insert(rec("x", 0), [](std::uint64_t) { throw std::runtime_error("disk full"); }), std::runtime_error);
  EXPECT_TRUE(s.all().empty());
  protocol::ProgressInfo p;
  p.spp = 12;
  p.rel_error = 0.5;
  std::uint64_t id = s.insert(rec("y", 0), {});
  s.set_progress(id, p);
  EXPECT_EQ(s.get(id)->progress.spp, 12u);
  EXPECT_EQ(*s.get(id)->progress.rel_error, 0.5);
  s.remove(id);
  EXPECT_FALSE(s.get(id));
}

TEST(JobStore, SamplerOverrideIsKeptAndOldStoresGainTheColumn) {
  TempDir t;
  std::string db = (t.p / "jobs.sqlite").string();
  {
    // A store written before the sampler column existed, with one queued job.
    sqlite3* raw = nullptr;
    ASSERT_EQ(sqlite3_open(db.c_str(), &raw), SQLITE_OK);
    ASSERT_EQ(sqlite3_exec(raw,
                           "CREATE TABLE jobs (id INTEGER PRIMARY KEY AUTOINCREMENT, name TEXT NOT NULL, owner TEXT NOT "
                           "NULL, priority INTEGER NOT NULL, state TEXT NOT NULL, halt_spp INTEGER, halt_time REAL, "
                           "halt_error REAL, seed INTEGER NOT NULL, integrator TEXT NOT NULL, pass INTEGER NOT NULL "
                           "DEFAULT 0, spp INTEGER NOT NULL DEFAULT 0, elapsed_s REAL NOT NULL DEFAULT 0, rel_error "
                           "REAL, samples_per_s REAL NOT NULL DEFAULT 0, message TEXT NOT NULL DEFAULT '', created TEXT "
                           "NOT NULL DEFAULT (datetime('now')));"
                           "INSERT INTO jobs (name, owner, priority, state, seed, integrator) "
                           "VALUES ('old', '1000', 0, 'queued', 3, 'bdpt');",
                           nullptr, nullptr, nullptr),
              SQLITE_OK);
    sqlite3_close(raw);
  }
  {
    JobStore s(db);
    EXPECT_EQ(s.get(1)->sampler, "");  // the scene's
    EXPECT_EQ(s.get(1)->integrator, "bdpt");
    JobRecord r = rec("new", 0);
    r.sampler = "independent";
    s.insert(r, {});
  }
  JobStore s(db);
  EXPECT_EQ(s.get(2)->sampler, "independent");
  EXPECT_EQ(s.get(1)->sampler, "");
}

}  // namespace
}  // namespace omega::daemon

namespace omega::daemon {
namespace {

TEST(JobStore, UnitsAreKeptAndRunningOnesRequeuedAfterACrash) {
  TempDir t;
  std::string db = (t.p / "jobs.sqlite").string();
  std::uint64_t id = 0;
  {
    JobStore s(db);
    JobRecord r = rec("w", 0);
    r.workers = 2;
    r.unit_spp = 8;
    id = s.insert(r, {});
    s.put_unit(UnitRecord{id, 0, 0, 8, UnitState::done, "", 1.5});
    s.put_unit(UnitRecord{id, 1, 8, 16, UnitState::running, "conn 3 (a)", 0});
  }
  JobStore s(db);  // as after kill -9: nothing else was written
  EXPECT_EQ(s.get(id)->workers, 2u);
  EXPECT_EQ(s.get(id)->unit_spp, 8u);
  s.requeue_running_units();
  auto u = s.units(id);
  ASSERT_EQ(u.size(), 2u);
  EXPECT_EQ(u[0].state, UnitState::done);
  EXPECT_EQ(u[0].time_s, 1.5);
  EXPECT_EQ(u[1].state, UnitState::queued);
  EXPECT_EQ(u[1].owner, "");
  EXPECT_EQ(u[1].begin, 8u);
  s.remove(id);
  EXPECT_TRUE(s.units(id).empty());
}

}  // namespace
}  // namespace omega::daemon
