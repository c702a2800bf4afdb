// batch --slurm without a cluster: the manifest's slurm keys, the sample split, the scripts (run by
// a real bash against a stand-in omega, so quoting is checked by execution), the sbatch argument
// vectors, and the parsers of squeue/scontrol output. The end-to-end run on a real cluster is
// tests/slurm/test_slurm_batch.py.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>

#include "batch_command.h"
#include "slurm_batch.h"
#include "batch_test_util.h"
#include "test_fake_daemon.h"

namespace omega::client {
namespace {

using test::TempDir;
namespace fs = std::filesystem;
using namespace omega::client::slurm;

using test::parse_error;

TEST(SlurmManifest, ParsesTheSlurmKeys) {
    TempDir d;
    const auto p = d.write("m.yaml", R"(retries: 5
output_dir: out
slurm:
  partition: render
  chunks: 8
  time_limit: "1-02:00:00"
  retries: 1
  cpus_per_task: 4
  sbatch_args: [--qos=high, "--comment=two words"]
  poll_interval: 1.5
  omega: bin/omega
  work_dir: /scratch/w
  keep_parts: true
jobs: [{scene: a.yaml, spp: 16}]
)");
    const BatchManifest m = parse_manifest(p.string());
    EXPECT_EQ(m.slurm.partition, "render");
    EXPECT_EQ(m.slurm.chunks, 8);
    EXPECT_EQ(m.slurm.time_limit, "1-02:00:00");
    EXPECT_EQ(m.slurm.retries, 1);
    EXPECT_EQ(m.retries, 5);
    EXPECT_EQ(m.slurm.cpus_per_task, 4);
    EXPECT_EQ(m.slurm.sbatch_args, (std::vector<std::string>{"--qos=high", "--comment=two words"}));
    EXPECT_EQ(m.slurm.poll_interval_s, 1.5);
    EXPECT_EQ(m.slurm.omega, fs::absolute(d.path / "bin/omega").string());
    EXPECT_EQ(m.slurm.work_dir, "/scratch/w");
    EXPECT_TRUE(m.slurm.keep_parts);
    EXPECT_EQ(m.output_dir, (d.path / "out").string());

    const BatchManifest dflt = parse_manifest(d.write("n.yaml", "jobs: [{scene: a.yaml}]\n").string());
    EXPECT_EQ(dflt.slurm.chunks, 4);
    EXPECT_EQ(dflt.slurm.poll_interval_s, 5.0);
    EXPECT_FALSE(dflt.slurm.partition);
    EXPECT_FALSE(dflt.slurm.retries);
}

TEST(SlurmManifest, ErrorsNameFileLineAndKey) {
    TempDir d;
    EXPECT_EQ(parse_error(d, "slurm: {chunk: 3}\njobs: [{scene: a.yaml}]\n"),
              ":1: slurm.chunk: unknown key (partition, chunks, time_limit, retries, cpus_per_task, sbatch_args, "
              "poll_interval, omega, work_dir, keep_parts)");
    EXPECT_EQ(parse_error(d, "slurm:\n  chunks: 0\njobs: [{scene: a.yaml}]\n"), ":2: slurm.chunks: must be in 1..10000");
    EXPECT_EQ(parse_error(d, "slurm: {poll_interval: 0.2}\njobs: [{scene: a.yaml}]\n"),
              ":1: slurm.poll_interval: at least 1 s (each poll queries the Slurm controller)");
    EXPECT_EQ(parse_error(d, "slurm: {time_limit: 1h}\njobs: [{scene: a.yaml}]\n"),
              ":1: slurm.time_limit: expected minutes, [D-]HH:MM:SS or UNLIMITED");
    EXPECT_EQ(parse_error(d, "slurm: {sbatch_args: --qos=high}\njobs: [{scene: a.yaml}]\n"),
              ":1: slurm.sbatch_args: expected a list of arguments, e.g. [--qos=high, --mem=2G]");
    EXPECT_EQ(parse_error(d, "slurm: {partition: a b}\njobs: [{scene: a.yaml}]\n"), ":1: slurm.partition: expected one word");
    EXPECT_EQ(parse_error(d, "slurm: [1]\njobs: [{scene: a.yaml}]\n"), ":1: slurm: expected a mapping");
}

TEST(SlurmPlan, SplitsSamplesEvenlyWithoutEmptyChunks) {
    auto s = split_samples(10, 4);
    ASSERT_EQ(s.size(), 4u);
    EXPECT_EQ(s[0].begin, 0u);
    EXPECT_EQ(s[0].end, 3u);
    EXPECT_EQ(s[1].end, 6u);
    EXPECT_EQ(s[2].end, 8u);
    EXPECT_EQ(s[3].begin, 8u);
    EXPECT_EQ(s[3].end, 10u);
    EXPECT_EQ(split_samples(2, 4).size(), 2u);
    EXPECT_EQ(split_samples(2, 4)[1].end, 2u);
    EXPECT_EQ(split_samples(7, 1).size(), 1u);
}

// A manifest whose paths hold every character a shell would trip on.
BatchManifest awkward_manifest(const TempDir& d) {
    const std::string dir = "it's $HOME `x` \"q\"";
    const auto p = d.write(dir + "/m.yaml", R"(slurm:
  chunks: 3
  partition: gpu
  time_limit: "10"
  sbatch_args: [--qos=high]
jobs:
  - {scene: "sc ene's.yaml", output: "out $1/f{frame}.exr", frames: [7, 8], spp: 10, seed: 3, integrator: bdpt}
)");
    return parse_manifest(p.string());
}

TEST(SlurmPlan, RenderScriptPassesPathsIntactToOmega) {
    TempDir d;
    const BatchManifest m = awkward_manifest(d);
    // A stand-in omega that writes its arguments, one per line.
    const auto fake = d.write("fake omega", "#!/bin/sh\nfor a in \"$@\"; do printf '%s\\n' \"$a\"; done > \"$ARGS_OUT\"\n");
    fs::permissions(fake, fs::perms::owner_all);
    const FramePlan f = plan_frame(m, 1, 10, fake.string());
    ASSERT_EQ(f.chunks.size(), 3u);
    const auto script = d.write("render.sh", f.render_text);
    const auto args_out = d.path / "args.txt";
    const std::string cmd = "ARGS_OUT=" + sh_quote(args_out.string()) + " SLURM_ARRAY_TASK_ID=2 bash " + sh_quote(script.string());
    ASSERT_EQ(std::system(cmd.c_str()), 0) << f.render_text;
    const std::string dir = (d.path / "it's $HOME `x` \"q\"").string();
    EXPECT_EQ(test::slurp(args_out), "render\n" + dir + "/sc ene's.yaml\n--samples\n7:10\n-o\n" + f.parts[2] +
                                         "\n--seed\n3\n--threads\n1\n--integrator\nbdpt\n");
    EXPECT_EQ(f.parts[2], f.work + "/part_2.exr");
    EXPECT_EQ(f.work, dir + "/.omega-slurm/0002-f8");
    // A task index the plan does not know is refused, not rendered as some other chunk.
    EXPECT_NE(std::system(("SLURM_ARRAY_TASK_ID=3 bash " + sh_quote(script.string()) + " 2>/dev/null").c_str()), 0);

    const auto merge = d.write("merge.sh", f.merge_text);
    ASSERT_EQ(std::system(("ARGS_OUT=" + sh_quote(args_out.string()) + " bash " + sh_quote(merge.string())).c_str()), 0);
    EXPECT_EQ(test::slurp(args_out), "merge\n" + f.parts[0] + "\n" + f.parts[1] + "\n" + f.parts[2] + "\n-o\n" + dir +
                                         "/out $1/f8.exr\n");
}

TEST(SlurmPlan, SbatchArgumentVectors) {
    TempDir d;
    const BatchManifest m = awkward_manifest(d);
    const FramePlan f = plan_frame(m, 0, 10, "/opt/omega");
    EXPECT_EQ(render_sbatch_args(m.slurm, f, "0-2"),
              (std::vector<std::string>{"--parsable", "--job-name=omega-render-f7", "--ntasks=1", "--chdir=" + f.work,
                                        "--partition=gpu", "--time=10", "--array=0-2", "--cpus-per-task=1",
                                        "--output=" + f.work + "/render_%A_%a.log", "--qos=high", f.render_script}));
    EXPECT_EQ(merge_sbatch_args(m.slurm, f, "afterok:12_0:15_2"),
              (std::vector<std::string>{"--parsable", "--job-name=omega-merge-f7", "--ntasks=1", "--chdir=" + f.work,
                                        "--partition=gpu", "--time=10", "--cpus-per-task=1",
                                        "--output=" + f.work + "/merge_%j.log", "--dependency=afterok:12_0:15_2",
                                        "--kill-on-invalid-dep=yes", "--qos=high", f.merge_script}));
    EXPECT_EQ(merge_sbatch_args(m.slurm, f, "").size(), 10u);  // a resubmitted merge after every chunk is done
}

TEST(SlurmState, ParsesSqueueAndScontrol) {
    const auto q = parse_squeue("12_1 RUNNING\n12_3 PENDING\n13 PENDING\n");
    EXPECT_EQ(q.size(), 3u);
    EXPECT_EQ(q.at("12_1"), "RUNNING");
    EXPECT_EQ(q.at("13"), "PENDING");

    const auto r = parse_scontrol(
        "JobId=14 ArrayJobId=12 ArrayTaskId=2-3%2 JobName=x UserId=root(0) JobState=PENDING Reason=Resources "
        "Dependency=(null) ExitCode=0:0 Command=/w/render.sh\n"
        "JobId=13 ArrayJobId=12 ArrayTaskId=1 JobState=CANCELLED Reason=None ExitCode=0:15\n"
        "JobId=12 ArrayJobId=12 ArrayTaskId=0 JobState=COMPLETED Reason=None ExitCode=0:0\n");
    ASSERT_EQ(r.size(), 3u);
    EXPECT_EQ(r[0].array_tasks, "2-3%2");
    EXPECT_EQ(r[0].state, "PENDING");
    EXPECT_EQ(r[1].job_id, "13");
    EXPECT_EQ(r[1].array_job_id, "12");
    EXPECT_EQ(r[1].exit_code, "0:15");
    EXPECT_EQ(r[2].state, "COMPLETED");
    EXPECT_TRUE(task_in_range("2-3%2", 3));
    EXPECT_FALSE(task_in_range("2-3%2", 1));
    EXPECT_TRUE(task_in_range("1,4-8:2", 6));
    EXPECT_FALSE(task_in_range("1,4-8:2", 5));
    EXPECT_TRUE(task_in_range("5", 5));
}

TEST(SlurmProcess, CollectsOutputAndStatusWithoutAShell) {
    const ProcResult r = run_process({"sh", "-c", "printf out; printf err >&2; exit 3"});
    EXPECT_EQ(r.status, 3);
    EXPECT_EQ(r.out, "out");
    EXPECT_EQ(r.err, "err");
    // An argument is one argv element, whatever it holds.
    EXPECT_EQ(run_process({"printf", "%s|", "a b", "$HOME", "'"}).out, "a b|$HOME|'|");
    EXPECT_EQ(run_process({"sh", "-c", "kill -TERM $$"}).status, 128 + 15);
    try {
        run_process({"omega-no-such-program"});
        FAIL() << "ran a missing program";
    } catch (const ClientError& e) {
        EXPECT_EQ(e.exit_code(), kExitUnreachable);
        EXPECT_STREQ(e.what(), "cannot run omega-no-such-program: No such file or directory");
    }
}

TEST(SlurmDryRun, PrintsScriptsAndCommandsAndRunsNoSlurmCommand) {
    TempDir d;
    d.write("a.yaml", "omega: 1\nlights: [{type: constant, radiance: 1}]\n");  // no halt: 64 spp
    const auto p = d.write("m.yaml", "slurm: {chunks: 2}\njobs:\n  - {scene: a.yaml}\n  - {scene: a.yaml, output: b.exr, spp: 3}\n");
    const BatchManifest m = parse_manifest(p.string());
    // No Slurm command may run: with an empty PATH, any attempt would fail the call.
    const std::string old_path = std::getenv("PATH") ? std::getenv("PATH") : "";
    setenv("PATH", (d.path / "empty").c_str(), 1);
    std::FILE* out = std::tmpfile();
    std::vector<BatchResult> r;
    EXPECT_NO_THROW(r = run_slurm_batch(m, true, out, nullptr));
    setenv("PATH", old_path.c_str(), 1);
    EXPECT_TRUE(r.empty());
    std::rewind(out);
    std::string text;
    for (int c; (c = std::fgetc(out)) != EOF;) text += char(c);
    std::fclose(out);
    EXPECT_NE(text.find("samples=0:32 "), std::string::npos) << text;
    EXPECT_NE(text.find("samples=32:64 "), std::string::npos) << text;
    EXPECT_NE(text.find("samples=2:3 "), std::string::npos) << text;
    EXPECT_NE(text.find("$ sbatch '--parsable' '--job-name=omega-render-a'"), std::string::npos) << text;
    EXPECT_NE(text.find("'--dependency=afterok:ARRAY_JOB_ID'"), std::string::npos) << text;
    EXPECT_FALSE(fs::exists(d.path / ".omega-slurm"));  // nothing written

    // A halt that is not a sample count cannot be split.
    const auto q = d.write("t.yaml", "jobs:\n  - {scene: a.yaml, time: 3}\n");
    try {
        run_slurm_batch(parse_manifest(q.string()), true, nullptr, nullptr);
        FAIL() << "a time halt was accepted";
    } catch (const ClientError& e) {
        EXPECT_EQ(e.exit_code(), kExitBadInput);
        EXPECT_EQ(std::string(e.what()), q.string() + ":2: a.yaml: --slurm splits a sample count; give the job `spp`, "
                                                      "not `time` or `target_error`");
    }
    // A bad scene stops the batch before anything is submitted.
    d.write("bad.yaml", "omega: 1\nshapes: 3\n");
    const auto b = d.write("b.yaml", "jobs:\n  - {scene: bad.yaml, spp: 4}\n");
    EXPECT_THROW(run_slurm_batch(parse_manifest(b.string()), true, nullptr, nullptr), ClientError);
}

}  // namespace
}  // namespace omega::client
