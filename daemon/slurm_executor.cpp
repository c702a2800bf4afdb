#include "daemon/slurm_executor.h"

#include <filesystem>
#include <sstream>
#include <stdexcept>

#include "daemon/checkpoint.h"
#include "io/process.h"

namespace omega::daemon {

namespace {

std::string trim(std::string s) {
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ' || s.back() == '\r')) s.pop_back();
  return s;
}

}  // namespace

std::string worker_script(const SlurmSettings& s, std::uint64_t job) {
  std::ostringstream o;
  o << "#!/bin/sh\n"
    << "# omegad: workers for job " << job << " (docs/farm.md \"Workers under Slurm\")\n"
    << "export OMEGA_USER=" << sh_quote(s.user) << "\n"
    << "export OMEGA_TOKEN_FILE=" << sh_quote(s.token_file) << "\n"
    << "unset OMEGA_TOKEN\n"
    << "exec " << sh_quote(s.omega) << " worker --connect " << sh_quote(s.connect) << " --threads " << s.threads
    << " --idle-exit " << s.idle_exit_s << " --name \"slurm-${SLURM_ARRAY_JOB_ID:-$SLURM_JOB_ID}_${SLURM_ARRAY_TASK_ID:-0}\"\n";
  return o.str();
}

std::string submit_workers(const SlurmSettings& s, const std::string& dir, std::uint64_t job, int count) {
  std::filesystem::create_directories(dir);
  const std::string script = dir + "/job-" + std::to_string(job) + ".sh";
  write_file_atomic(script, worker_script(s, job));
  std::filesystem::permissions(script, std::filesystem::perms::owner_all);
  std::vector<std::string> argv{"sbatch", "--parsable", "--job-name=omega-worker-" + std::to_string(job),
                                "--array=0-" + std::to_string(count - 1),
                                "--output=" + dir + "/job-" + std::to_string(job) + "-%A_%a.log"};
  if (!s.partition.empty()) argv.push_back("--partition=" + s.partition);
  if (!s.time_limit.empty()) argv.push_back("--time=" + s.time_limit);
  argv.insert(argv.end(), s.sbatch_options.begin(), s.sbatch_options.end());
  argv.push_back(script);
  ProcessResult p = run_captured(argv);
  if (p.status != 0) throw std::runtime_error("sbatch exited " + std::to_string(p.status) + ": " + trim(p.err));
  std::string id = trim(p.out);
  id = id.substr(0, id.find(';'));  // --parsable: "ID" or "ID;CLUSTER"
  if (id.empty() || id.find_first_not_of("0123456789") != std::string::npos)
    throw std::runtime_error("sbatch printed no job id: '" + trim(p.out) + "'");
  return id;
}

std::string cancel_workers(const std::vector<std::string>& ids) {
  if (ids.empty()) return {};
  std::vector<std::string> argv{"scancel"};
  argv.insert(argv.end(), ids.begin(), ids.end());
  try {
    ProcessResult p = run_captured(argv);
    return p.status == 0 ? std::string() : "scancel exited " + std::to_string(p.status) + ": " + trim(p.err);
  } catch (const std::exception& e) {
    return e.what();
  }
}

std::map<std::string, int> alive_tasks(const std::vector<std::string>& ids) {
  std::map<std::string, int> alive;
  if (ids.empty()) return alive;
  std::string list;
  for (const auto& id : ids) list += (list.empty() ? "" : ",") + id;
  // -r: one line per array task; %F the array's job id, %T its state. Ended tasks are absent.
  ProcessResult p = run_captured({"squeue", "-h", "-r", "-j", list, "-o", "%F %T"});
  if (p.status != 0 && p.err.find("Invalid job id") == std::string::npos)
    throw std::runtime_error("squeue exited " + std::to_string(p.status) + ": " + trim(p.err));
  std::istringstream in(p.out);
  std::string id, state;
  while (in >> id >> state)
    if (state == "PENDING" || state == "RUNNING" || state == "CONFIGURING" || state == "REQUEUED" ||
        state == "RESIZING" || state == "SUSPENDED")
      alive[id] += 1;
  return alive;
}

}  // namespace omega::daemon
