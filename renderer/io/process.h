#pragma once
// Running a helper program and collecting its output: Slurm's own commands (sbatch, squeue,
// scontrol, sacct), for both omegad's executor and `omega batch`.
#include <stdexcept>
#include <string>
#include <vector>

namespace omega {

struct ProcessResult {
    int status = -1;  // exit status, or 128 + signal
    std::string out, err;
};

// The program could not be started (not in PATH, not executable).
struct ProcessSpawnError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// Runs argv[0] (looked up in PATH) with argv, stdin from /dev/null, and collects stdout and
// stderr until both close. Blocks the calling thread (any thread). Throws ProcessSpawnError
// ("cannot run NAME: reason") or std::runtime_error when no pipe can be made.
ProcessResult run_captured(const std::vector<std::string>& argv);

// s as one single-quoted sh word (a quote inside becomes '\''), for generated job scripts.
std::string sh_quote(const std::string& s);

}  // namespace omega
