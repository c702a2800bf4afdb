// omegad: the render daemon. Parses the command line and hands over to Server.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>

#include "daemon/log.h"
#include "daemon/server.h"
#include "daemon/signals.h"

int main(int argc, char** argv) {
  CLI::App app{"omegad: the Omega render daemon"};
  std::string config_path;
  std::vector<std::string> listen;
  std::string state_dir;
  int threads = -1;
  app.add_option("--config", config_path, "YAML config file (see docs/daemon.md)");
  app.add_option("--listen", listen, "unix:PATH or tcp:HOST:PORT (loopback only); repeatable")->take_all();
  app.add_option("--state-dir", state_dir, "Job store, checkpoints, results and the asset cache");
  app.add_option("--threads", threads, "Render worker threads (0: all cores)")->check(CLI::NonNegativeNumber);
  CLI11_PARSE(app, argc, argv);

  // Before any thread exists, so that every thread inherits the mask (signals arrive via signalfd).
  omega::daemon::block_daemon_signals();
  omega::daemon::Log log;
  auto overrides = [=](omega::daemon::Config& c) {
    if (!listen.empty()) c.listen = listen;
    if (!state_dir.empty()) c.state_dir = state_dir;
    if (threads >= 0) c.threads = threads;
  };
  try {
    omega::daemon::Server server(config_path, overrides, log);
    server.start();
    return server.run();
  } catch (const std::exception& e) {
    log.error("omegad: {}", e.what());
    return 1;
  }
}
