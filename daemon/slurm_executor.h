#pragma once
// `executor: slurm` (docs/farm.md "Workers under Slurm"): omegad asks Slurm for `omega worker`
// processes for a worker job with `sbatch --parsable --array`, watches them with `squeue`, and
// `scancel`s them when the job ends, is paused or cancelled. These functions only run Slurm's
// commands and read their output; they block for the command (~0.1 s), so the loop thread calls
// them on the background thread. No state: the Slurm job ids live in the job store.
#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace omega::daemon {

struct SlurmSettings {
  std::string omega = "omega";   // the omega binary on the nodes
  std::string connect;           // ADDR the workers connect back to (tcp:HOST:PORT)
  std::string user;              // a tcp_users entry with role worker
  std::string token_file;        // its token, a 0600 file the nodes can read (shared FS)
  int threads = 0;               // per worker (0: the node's cores)
  std::string partition;         // empty: Slurm's default
  std::string time_limit;        // sbatch --time; empty: the partition's
  std::vector<std::string> sbatch_options;  // extra sbatch arguments, e.g. --mem=8G
  double poll_s = 5;             // squeue at most this often
  double idle_exit_s = 60;       // a worker with no unit this long exits (frees its allocation)
  int max_replacements = 8;      // per job: workers started again after Slurm reported them ended
};

// The batch script of a job's workers. The token is not in it: the script names the token file
// (and the user) in the environment, so neither appears on a command line that `ps` shows.
std::string worker_script(const SlurmSettings& s, std::uint64_t job);

// Any thread but the loop's. Writes the script under dir, runs sbatch for `count` array tasks and
// returns the Slurm job id. Throws std::runtime_error with sbatch's message.
std::string submit_workers(const SlurmSettings& s, const std::string& dir, std::uint64_t job, int count);
// scancel of the given Slurm job ids; returns what failed (empty: all fine). Never throws.
std::string cancel_workers(const std::vector<std::string>& ids);
// squeue -r: the array tasks still pending or running, per Slurm job id (an id that is absent has
// ended). Throws std::runtime_error when squeue fails.
std::map<std::string, int> alive_tasks(const std::vector<std::string>& ids);

}  // namespace omega::daemon
