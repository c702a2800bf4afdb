#pragma once
// `omega worker --connect ADDR`: a render process that pulls work units (sample ranges of jobs)
// from omegad, renders each exactly as `omega render --samples A:B` would, and sends the part
// back. Started by hand, by a systemd unit or by Slurm. docs/farm.md "Workers".
#include <CLI/CLI.hpp>

#include <optional>
#include <string>

namespace omega::client {

struct WorkerArgs {
    std::optional<std::string> connect;  // ADDR; default as for --host
    int threads = 0;                     // 0: all cores
    std::string name;                    // shown by `omega status JOB`; default host:pid
    std::string cache_dir;               // scenes and assets by hash; default $TMPDIR/omega-worker-UID
    bool once = false;                   // exit when the daemon has no unit (tests, batch scripts)
    double idle_exit_s = 0;              // exit after this long without a unit (0: never; --once: 3)
    bool quiet = false;
};

void add_worker_command(CLI::App& app, WorkerArgs& args);
int run_worker(const WorkerArgs& args);

}  // namespace omega::client
