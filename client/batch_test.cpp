// batch: the manifest format, the concurrency limit, retry of a transient failure, the summary.
#include <gtest/gtest.h>

#include <map>
#include <mutex>
#include <set>

#include "batch_command.h"
#include "batch_test_util.h"
#include "test_fake_daemon.h"

namespace omega::client {
namespace {

namespace proto = omega::protocol;
using test::FakeDaemon;
using test::TempDir;
namespace fs = std::filesystem;

const char* kScene = "omega: 1\nlights: [{type: constant, radiance: 1}]\n";

using test::parse_error;

TEST(BatchManifest, ExpandsFramesAndMatrixWithDefaults) {
    TempDir d;
    const auto p = d.write("m.yaml", R"(concurrency: 3
retries: 1
output_dir: renders
defaults: {spp: 16, seed: 2}
jobs:
  - scene: shots/a.yaml
    priority: 5
  - scene: anim/f{frame:03}.yaml
    frames: [9, 11]
    output: anim_{frame:03}.exr
  - scene: stereo_{eye}.yaml
    matrix: {eye: [left, right], take: [1, 2]}
    time: 30
  - scene: shots/b.yaml
    matrix: {seed: [7, 8]}
    output: b_{seed}.exr
)");
    BatchManifest m = parse_manifest(p.string());
    EXPECT_EQ(m.concurrency, 3);
    EXPECT_EQ(m.retries, 1);
    ASSERT_EQ(m.jobs.size(), 1u + 3u + 4u + 2u);
    const std::string dir = d.path.string();
    EXPECT_EQ(m.jobs[0].scene, dir + "/shots/a.yaml");
    EXPECT_EQ(m.jobs[0].output, dir + "/renders/a.exr");
    EXPECT_EQ(m.jobs[0].spec.priority, 5);
    EXPECT_EQ(m.jobs[0].spec.halt.spp, 16u);
    EXPECT_EQ(m.jobs[0].spec.seed, 2u);
    EXPECT_EQ(m.jobs[0].where, p.string() + ":6");
    EXPECT_EQ(m.jobs[1].scene, dir + "/anim/f009.yaml");
    EXPECT_EQ(m.jobs[3].output, dir + "/renders/anim_011.exr");
    EXPECT_EQ(m.jobs[3].label, "anim/f011.yaml frame=11");
    // The job's own halt replaces the defaults' (time here, not spp 16).
    EXPECT_EQ(m.jobs[4].spec.halt.time_s, 30.0);
    EXPECT_FALSE(m.jobs[4].spec.halt.spp);
    EXPECT_EQ(m.jobs[4].scene, dir + "/stereo_left.yaml");
    EXPECT_EQ(m.jobs[4].output, dir + "/renders/stereo_left_left_1.exr");
    EXPECT_EQ(m.jobs[7].label, "stereo_right.yaml eye=right take=2");
    // A variable named like a job key sets it.
    EXPECT_EQ(m.jobs[8].spec.seed, 7u);
    EXPECT_EQ(m.jobs[9].spec.seed, 8u);
    EXPECT_EQ(m.jobs[9].output, dir + "/renders/b_8.exr");
    EXPECT_EQ(parse_error(d, "jobs:\n  - {scene: a.yaml, matrix: {seed: [1, x]}, output: '{seed}.exr'}\n"),
              ":2: jobs[0].matrix.seed: 'x' is not a valid seed");
}

TEST(BatchManifest, ErrorsNameFileAndLine) {
    TempDir d;
    EXPECT_EQ(parse_error(d, "jobs:\n  - scene: a.yaml\n    sppp: 3\n"), ":3: jobs[0].sppp: unknown key (scene, output, "
                                                                          "priority, spp, time, target_error, seed, "
                                                                          "integrator, frames, matrix)");
    EXPECT_EQ(parse_error(d, "jobs:\n  - output: a.exr\n"), ":2: jobs[0].scene: missing");
    EXPECT_EQ(parse_error(d, "jobs:\n  - {scene: a.yaml, spp: -1}\n"), ":2: jobs[0].spp: must be in 1..1099511627776");
    EXPECT_EQ(parse_error(d, "jobs:\n  - {scene: a.yaml}\n  - {scene: b/a.yaml, output: a.exr}\n"),
              ":3: jobs[1]: output " + (d.path / "a.exr").string() + " is also written by the job at " +
                  (d.path / "m.yaml").string() + ":2");
    EXPECT_EQ(parse_error(d, "concurrency: 0\njobs: [{scene: a.yaml}]\n"), ":1: concurrency: must be in 1..1024");
    EXPECT_EQ(parse_error(d, "jobs: []\n"), ":1: jobs: expected a non-empty list");
    EXPECT_EQ(parse_error(d, "jobs:\n  - {scene: a.yaml, frames: [1, 3]}\n").substr(0, 3), "(ac");  // default outputs differ
    EXPECT_EQ(parse_error(d, "jobs:\n  - {scene: a.yaml, frames: [1, 3], output: x.exr}\n"),
              ":2: jobs[0].output: with frames or matrix, the output must use them, e.g. out_{frame:04}.exr");
    EXPECT_EQ(parse_error(d, "jobs:\n  - {scene: a.yaml\n").substr(0, 16), ":3: invalid YAML");
    EXPECT_EQ(parse_error(d, "jobs:\n  - {scene: a.yaml, spp: 4, time: 3}\n"), ":2: jobs[0]: give at most one of spp, time, target_error");
}

// A daemon whose jobs end after a few status polls. The second job submitted fails once.
struct FarmDaemon {
    std::mutex mu;
    uint64_t next_job = 1;
    std::map<uint64_t, int> polls;     // job -> status polls so far
    std::map<uint64_t, std::string> scene_of;
    int in_flight = 0, max_in_flight = 0, submits = 0;
    std::set<uint64_t> failing{2};
    FakeDaemon fake;

    FarmDaemon()
        : fake([this](FakeDaemon::Session& s, const proto::DecodedFrame& f) { handle(s, f); }) {}

    void handle(FakeDaemon::Session& s, const proto::DecodedFrame& f) {
        std::lock_guard lock(mu);
        if (f.type == proto::MessageType::submit) {
            auto sub = proto::decode<proto::Submit>(f).value();
            const uint64_t job = next_job++;
            ++submits;
            scene_of[job] = sub.name;
            max_in_flight = std::max(max_in_flight, ++in_flight);
            s.reply(proto::NeedAssets{f.id, {}});
            s.reply(proto::Accepted{f.id, job});
        } else if (f.type == proto::MessageType::status) {
            const uint64_t job = proto::decode<proto::Status>(f).value().job;
            proto::JobInfo i;
            i.job = job;
            i.state = proto::JobState::running;
            if (++polls[job] >= 3) {
                i.state = failing.count(job) ? proto::JobState::failed : proto::JobState::done;
                if (polls[job] == 3) --in_flight;
            }
            i.progress.spp = 16;
            i.progress.elapsed_s = 1.5;
            s.reply(proto::JobInfoReply{f.id, i});
        } else if (f.type == proto::MessageType::fetch) {
            const uint64_t job = proto::decode<proto::Fetch>(f).value().job;
            s.reply(proto::Image{f.id, job, 4, 16, 1, 1, "image of job " + std::to_string(job)});
        }
    }
};

TEST(Batch, ConcurrencyLimitRetryAndSummary) {
    TempDir d;
    d.write("s.yaml", kScene);
    FarmDaemon farm;
    const auto mp = d.write("m.yaml", "host: " + farm.fake.address() + R"(
concurrency: 2
retries: 2
retry_delay: 0.01
poll_interval: 0.01
output_dir: out
defaults: {spp: 16}
jobs:
  - scene: s.yaml
    frames: [1, 4]
    output: f_{frame:02}.exr
  - {scene: s.yaml, output: single.exr, priority: 3}
)");
    BatchArgs a;
    a.manifest = mp.string();
    testing::internal::CaptureStdout();
    testing::internal::CaptureStderr();
    EXPECT_EQ(run_batch(a), kExitOk);
    const std::string out = testing::internal::GetCapturedStdout();
    const std::string err = testing::internal::GetCapturedStderr();

    std::lock_guard lock(farm.mu);
    EXPECT_EQ(farm.max_in_flight, 2) << err;  // the limit, and used
    EXPECT_EQ(farm.submits, 6);              // five jobs, one of them twice
    EXPECT_NE(err.find("retrying (attempt 2/3) after: job 2 failed"), std::string::npos) << err;
    // Every output written with the image of the job that finished it.
    std::set<std::string> images;
    for (const char* o : {"f_01.exr", "f_02.exr", "f_03.exr", "f_04.exr", "single.exr"}) {
        const std::string img = test::slurp(d.path / "out" / o);
        EXPECT_EQ(img.rfind("image of job ", 0), 0u) << o;
        EXPECT_NE(img, "image of job 2");
        images.insert(img);
    }
    EXPECT_EQ(images.size(), 5u);
    EXPECT_EQ(out.substr(0, 3), "#  ");
    EXPECT_NE(out.find("JOB  STATE  TRIES  SPP  TIME  OUTPUT"), std::string::npos) << out;
    EXPECT_NE(out.find("s.yaml frame=2  "), std::string::npos) << out;
    EXPECT_NE(out.find("done   2      16   1.5s"), std::string::npos) << out;  // the retried one
    EXPECT_NE(out.find("5 of 5 job(s) done, 0 failed"), std::string::npos) << out;
}

TEST(Batch, GivesUpAfterRetriesAndReportsIt) {
    TempDir d;
    d.write("s.yaml", kScene);
    FarmDaemon farm;
    farm.failing = {1, 2, 3};
    const auto mp = d.write("m.yaml", "host: " + farm.fake.address() +
                                          "\nretries: 2\nretry_delay: 0\npoll_interval: 0.001\njobs: [{scene: s.yaml}]\n");
    BatchArgs a;
    a.manifest = mp.string();
    testing::internal::CaptureStdout();
    testing::internal::CaptureStderr();
    EXPECT_EQ(run_batch(a), kExitInternal);
    const std::string out = testing::internal::GetCapturedStdout();
    const std::string err = testing::internal::GetCapturedStderr();
    EXPECT_NE(out.find("failed  3      -    -     job 3 failed"), std::string::npos) << out;
    EXPECT_NE(out.find("0 of 1 job(s) done, 1 failed"), std::string::npos) << out;
    EXPECT_NE(err.find("gave up after 3 attempt(s)"), std::string::npos) << err;
}

TEST(Batch, BadSceneStopsBeforeAnythingIsSent) {
    TempDir d;
    d.write("s.yaml", kScene);
    d.write("bad.yaml", "omega: 1\nshapes:\n  - {type: blob}\n");
    FarmDaemon farm;
    const auto mp = d.write("m.yaml", "host: " + farm.fake.address() + "\njobs:\n  - {scene: s.yaml}\n  - {scene: bad.yaml}\n");
    BatchArgs a;
    a.manifest = mp.string();
    testing::internal::CaptureStderr();
    EXPECT_EQ(run_batch(a), kExitBadInput);
    const std::string err = testing::internal::GetCapturedStderr();
    EXPECT_NE(err.find("bad.yaml:3:"), std::string::npos) << err;
    EXPECT_NE(err.find("m.yaml:4"), std::string::npos) << err;
    std::lock_guard lock(farm.mu);
    EXPECT_EQ(farm.submits, 0);
}

TEST(Batch, UnreachableDaemonExits3) {
    TempDir d;
    d.write("s.yaml", kScene);
    const auto mp = d.write("m.yaml", "host: unix:" + (d.path / "none.sock").string() +
                                          "\nretries: 1\nretry_delay: 0\njobs: [{scene: s.yaml}]\n");
    BatchArgs a;
    a.manifest = mp.string();
    testing::internal::CaptureStdout();
    testing::internal::CaptureStderr();
    EXPECT_EQ(run_batch(a), kExitUnreachable);
    const std::string out = testing::internal::GetCapturedStdout();
    testing::internal::GetCapturedStderr();
    EXPECT_NE(out.find("cannot reach the daemon at unix:"), std::string::npos) << out;
}

}  // namespace
}  // namespace omega::client
