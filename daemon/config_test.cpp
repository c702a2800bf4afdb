#include "daemon/config.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace omega::daemon {
namespace {

// Writes text to a temp config file and loads it.
Config load(const std::string& text) {
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("omegad-config-" + std::to_string(::getpid()) + ".yaml")).string();
  {
    std::ofstream out(path);
    out << text;
  }
  struct Remove {
    std::string p;
    ~Remove() { std::filesystem::remove(p); }
  } remove{path};
  return load_config(path);
}

std::string error_of(const std::string& text) {
  try {
    load(text);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

TEST(Config, WorkerRoleAndWorkerDefaults) {
  Config c = load(
      "tcp_users:\n  alice: alice-token-0123456789\n"
      "  farm: {token: farm-token-0123456789, role: worker}\n"
      "  bob: {token: bob-token-0123456789, role: user}\n"
      "workers: 4\nunit_seconds: 2.5\n");
  EXPECT_EQ(c.tcp_users.at("farm"), "farm-token-0123456789");
  EXPECT_EQ(c.worker_users, std::set<std::string>{"farm"});
  EXPECT_EQ(c.workers, 4);
  EXPECT_EQ(c.unit_seconds, 2.5);
  EXPECT_EQ(c.executor, "local");
  EXPECT_NE(error_of("tcp_users:\n  farm: {token: farm-token-0123456789, role: boss}\n").find("expected user or worker"),
            std::string::npos);
  EXPECT_NE(error_of("unit_seconds: 0\n").find("unit_seconds"), std::string::npos);
}

TEST(Config, SlurmExecutorNeedsAWorkerIdentity) {
  const std::string users = "tcp_users:\n  farm: {token: farm-token-0123456789, role: worker}\n  alice: alice-token-0123456789\n";
  Config c = load(users +
                  "executor: slurm\nslurm: {connect: 'tcp:head:7411', user: farm, token_file: /shared/farm.token, "
                  "threads: 8, partition: render, sbatch_options: [--mem=8G], poll_s: 2}\n");
  EXPECT_EQ(c.executor, "slurm");
  EXPECT_EQ(c.slurm.connect, "tcp:head:7411");
  EXPECT_EQ(c.slurm.threads, 8);
  EXPECT_EQ(c.slurm.sbatch_options, std::vector<std::string>{"--mem=8G"});
  EXPECT_NE(error_of(users + "executor: slurm\nslurm: {connect: 'tcp:h:1', user: alice, token_file: /t}\n")
                .find("role: worker"),
            std::string::npos);
  EXPECT_NE(error_of(users + "executor: slurm\nslurm: {user: farm, token_file: /t}\n").find("slurm.connect"),
            std::string::npos);
  EXPECT_NE(error_of(users + "slurm: {nodes: 3}\n").find("slurm.nodes"), std::string::npos);
  EXPECT_NE(error_of("executor: k8s\n").find("executor"), std::string::npos);
}

TEST(Config, SlurmWorkerScriptCarriesNoToken) {
  SlurmSettings s;
  s.omega = "/opt/omega bin/omega";
  s.connect = "tcp:head:7411";
  s.user = "farm";
  s.token_file = "/shared/farm.token";
  s.threads = 4;
  const std::string script = worker_script(s, 12);
  EXPECT_NE(script.find("export OMEGA_TOKEN_FILE='/shared/farm.token'"), std::string::npos) << script;
  EXPECT_NE(script.find("exec '/opt/omega bin/omega' worker --connect 'tcp:head:7411' --threads 4"), std::string::npos)
      << script;
  EXPECT_EQ(script.find("farm-token"), std::string::npos);
}

TEST(Config, AKeyGivenTwiceIsRefusedWithBothLines) {
  // yaml-cpp keeps both and reads the first: an override appended to the file went unnoticed.
  const std::string top = error_of("max_running: 1\nthreads: 2\nmax_running: 4\n");
  EXPECT_NE(top.find(":3: max_running: given twice (first at line 1)"), std::string::npos) << top;
  const std::string users = error_of("tcp_users:\n  alice: aaaaaaaaaaaaaaaaaaaa\n  alice: bbbbbbbbbbbbbbbbbbbb\n");
  EXPECT_NE(users.find(":3: tcp_users.alice: given twice (first at line 2)"), std::string::npos) << users;
  const std::string slurm = error_of("slurm:\n  threads: 2\n  threads: 8\n");
  EXPECT_NE(slurm.find(":3: slurm.threads: given twice (first at line 2)"), std::string::npos) << slurm;
  EXPECT_EQ(load("max_running: 3\n").max_running, 3);
}

}  // namespace
}  // namespace omega::daemon
