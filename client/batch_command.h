#pragma once
// `omega batch MANIFEST.yaml`: farm-style rendering of many scenes, sensors or frames. Submits
// with a concurrency limit, waits, retries transient failures, writes every output, and ends
// with a summary table. The manifest format is in docs/client.md.
#include <CLI/CLI.hpp>

#include <optional>
#include <string>
#include <vector>

#include "submit_command.h"

namespace omega::client {

struct BatchEntry {
    std::string label;   // for messages: the scene (and matrix values)
    std::string scene;   // path, resolved against the manifest's folder
    std::string output;  // path, resolved against output_dir
    JobSpec spec;
    std::string where;   // "manifest.yaml:12" of its jobs[] item
};

// The manifest's `slurm:` mapping: how `omega batch --slurm` splits and submits each job
// (docs/client.md, "batch --slurm").
struct SlurmSettings {
    std::optional<std::string> partition;   // sbatch --partition
    int chunks = 4;                         // sample chunks (array tasks) per job
    std::optional<std::string> time_limit;  // sbatch --time, per task
    std::optional<int> retries;             // resubmissions per chunk and merge; default: the manifest's
    int cpus_per_task = 1;                  // sbatch --cpus-per-task, and render --threads
    std::vector<std::string> sbatch_args;   // extra sbatch arguments, one per element
    double poll_interval_s = 5.0;           // seconds between squeue polls, at least kMinPollInterval
    std::optional<std::string> omega;       // the omega binary on the nodes; default: this one
    std::optional<std::string> work_dir;    // scripts, parts, logs; default: output_dir/.omega-slurm
    bool keep_parts = false;                // keep the partial EXRs after a successful merge
    static constexpr double kMinPollInterval = 1.0;
};

struct BatchManifest {
    std::string path;
    std::string output_dir;  // where relative outputs go (resolved)
    std::optional<std::string> host;
    int concurrency = 2;
    int retries = 2;
    double retry_delay_s = 1.0;
    double poll_interval_s = 0.5;
    std::vector<BatchEntry> jobs;
    SlurmSettings slurm;  // used by --slurm only
};

// Throws ClientError (exit 2) with "file:line: key: what" for anything wrong.
BatchManifest parse_manifest(const std::string& path);

struct BatchResult {
    const BatchEntry* entry = nullptr;
    std::optional<uint64_t> job;  // the last job id the daemon gave it
    std::string state = "pending";  // done, failed, cancelled, error
    int attempts = 0;
    uint64_t spp = 0;
    double elapsed_s = 0;
    int exit_code = 0;
    std::string message;  // why it did not finish
};

// Runs every entry (the manifest's scenes must already scan cleanly) and returns one result
// per entry, in manifest order. Progress lines go to log (may be null).
std::vector<BatchResult> run_batch_jobs(const BatchManifest& m, const std::optional<std::string>& host_flag,
                                        std::FILE* log);
std::string format_summary(const std::vector<BatchResult>& results);

struct BatchArgs {
    std::string manifest;
    std::optional<std::string> host;
    std::optional<int> concurrency;
    bool slurm = false;    // submit to Slurm instead of omegad
    bool dry_run = false;  // with --slurm: print the scripts and sbatch commands, submit nothing
};

void add_batch_command(CLI::App& app, BatchArgs& args);
int run_batch(const BatchArgs& args);

}  // namespace omega::client
