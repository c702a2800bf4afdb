#pragma once
// Remote commands on jobs: watch (stream tiles into an EXR), fetch (one image), status, list,
// cancel, pause, resume.
#include <CLI/CLI.hpp>

#include <optional>
#include <string>

namespace omega::client {

struct JobArgs {
    std::optional<std::string> host;
    std::optional<uint64_t> job;  // required except for `status`
    std::string output;           // watch, fetch
    bool quiet = false;           // watch
    double write_interval_s = 0.5;  // watch: how often OUT.exr is replaced while tiles stream in
};

struct JobCommands {
    JobArgs watch, fetch, status, list, cancel, pause, resume;
};

void add_job_commands(CLI::App& app, JobCommands& args);
// Dispatches on the parsed subcommand; returns -1 when none of these ran.
int run_job_command(const CLI::App& app, const JobCommands& args);

int run_watch(const JobArgs& a);
int run_fetch(const JobArgs& a);
int run_status(const JobArgs& a);
int run_list(const JobArgs& a);
int run_cancel(const JobArgs& a);
int run_pause(const JobArgs& a);
int run_resume(const JobArgs& a);

}  // namespace omega::client
