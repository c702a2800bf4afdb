#include "daemon/slurm_executor.h"

#include <fcntl.h>
#include <poll.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include "daemon/checkpoint.h"

extern char** environ;

namespace omega::daemon {

namespace {

struct Proc {
  int status = -1;
  std::string out, err;
};

// Runs argv (PATH lookup), stdin from /dev/null, and collects stdout and stderr. Blocks.
Proc run(const std::vector<std::string>& argv) {
  int out[2], err[2];
  if (pipe2(out, O_CLOEXEC) != 0) throw std::runtime_error(std::string("pipe: ") + std::strerror(errno));
  if (pipe2(err, O_CLOEXEC) != 0) {
    ::close(out[0]);
    ::close(out[1]);
    throw std::runtime_error(std::string("pipe: ") + std::strerror(errno));
  }
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_adddup2(&fa, out[1], 1);
  posix_spawn_file_actions_adddup2(&fa, err[1], 2);
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_t pid = 0;
  const int rc = posix_spawnp(&pid, args[0], &fa, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  ::close(out[1]);
  ::close(err[1]);
  if (rc != 0) {
    ::close(out[0]);
    ::close(err[0]);
    throw std::runtime_error("cannot run " + argv[0] + ": " + std::strerror(rc));
  }
  Proc r;
  pollfd fds[2] = {{out[0], POLLIN, 0}, {err[0], POLLIN, 0}};
  std::string* bufs[2] = {&r.out, &r.err};
  int open_fds = 2;
  while (open_fds > 0) {
    if (::poll(fds, 2, -1) < 0) {
      if (errno == EINTR) continue;
      break;
    }
    for (int i = 0; i < 2; ++i) {
      if (fds[i].fd < 0 || !(fds[i].revents & (POLLIN | POLLHUP | POLLERR))) continue;
      char buf[4096];
      const ssize_t n = ::read(fds[i].fd, buf, sizeof buf);
      if (n > 0) {
        bufs[i]->append(buf, std::size_t(n));
      } else if (n == 0 || errno != EINTR) {
        ::close(fds[i].fd);
        fds[i].fd = -1;
        --open_fds;
      }
    }
  }
  for (auto& p : fds)
    if (p.fd >= 0) ::close(p.fd);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  r.status = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return r;
}

// Single-quoted for sh.
std::string sh_quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

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
  Proc p = run(argv);
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
    Proc p = run(argv);
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
  Proc p = run({"squeue", "-h", "-r", "-j", list, "-o", "%F %T"});
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
