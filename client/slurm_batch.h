#pragma once
// `omega batch MANIFEST --slurm`: every manifest job becomes one Slurm job array whose tasks each
// render one sample chunk (`omega render --samples A:B`), plus one merge job (`omega merge`) that
// runs afterok of the chunks. The client waits, resubmits failed chunks (and a merge depending on
// the replacements), and ends with batch's summary table. docs/client.md, "batch --slurm".
// Slurm is driven only through its commands (sbatch, squeue, scontrol, scancel, sacct), each run
// from an argument vector, never through a shell.
#include <cstdint>
#include <cstdio>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "io/process.h"

#include "batch_command.h"

namespace omega::client::slurm {

struct Chunk {
    uint64_t begin = 0, end = 0;  // sample indices [begin, end)
};

// [0, spp) in at most `chunks` contiguous ranges whose sizes differ by at most one (fewer when
// spp < chunks: no chunk is empty).
std::vector<Chunk> split_samples(uint64_t spp, int chunks);

// Everything about one manifest job that the scripts and sbatch calls need.
struct FramePlan {
    const BatchEntry* entry = nullptr;
    uint64_t spp = 0;
    std::vector<Chunk> chunks;
    std::string scene, output;  // absolute: the tasks run in the work folder, on other machines
    std::string omega;   // binary on the nodes
    std::string work;    // folder for scripts, parts and logs
    std::string render_script, merge_script;  // paths in work
    std::string render_text, merge_text;      // their contents
    std::vector<std::string> parts;           // part EXR per chunk
};

// index: the job's position in the manifest (names its work folder).
FramePlan plan_frame(const BatchManifest& m, size_t index, uint64_t spp, const std::string& omega_bin);

// sbatch's arguments (without "sbatch") for the render array: `tasks` is the --array spec, "0-3"
// for the first submission, "2" for a resubmitted chunk (so SLURM_ARRAY_TASK_ID still picks it).
std::vector<std::string> render_sbatch_args(const SlurmSettings& s, const FramePlan& f, const std::string& tasks);
// ... and for the merge job; `dependency` e.g. "afterok:12" or "afterok:12_0:15_2" (empty: none).
std::vector<std::string> merge_sbatch_args(const SlurmSettings& s, const FramePlan& f, const std::string& dependency);

using ProcResult = ProcessResult;  // io/process.h
// Runs argv[0] (looked up in PATH) with argv, stdin from /dev/null, and collects its output.
// Throws ClientError (exit 3) when the program cannot be started.
ProcResult run_process(const std::vector<std::string>& argv);

// One record of `scontrol -o show job`: a job, an array task, or an array's pending remainder.
struct JobRecord {
    std::string job_id;        // JobId
    std::string array_job_id;  // ArrayJobId (empty for a plain job)
    std::string array_tasks;   // ArrayTaskId: "2", or "1-3,5%2" for tasks not yet started
    std::string state;         // JobState
    std::string reason;        // Reason
    std::string exit_code;     // ExitCode, "status:signal"
};
std::vector<JobRecord> parse_scontrol(const std::string& out);
// Does an ArrayTaskId value ("1-3,5", "0-7:2%4") include task k?
bool task_in_range(const std::string& spec, int k);
// `squeue -h -r -o "%i %T"`: "12_3" or "12" -> state.
std::map<std::string, std::string> parse_squeue(const std::string& out);

// Plans, submits and waits for every job of the manifest; one result per job in manifest order.
// With dry_run, prints every script and sbatch command to out and returns no results.
// Progress lines (the Slurm job ids, resubmissions) go to log (may be null).
std::vector<BatchResult> run_slurm_batch(const BatchManifest& m, bool dry_run, std::FILE* out, std::FILE* log);

}  // namespace omega::client::slurm
