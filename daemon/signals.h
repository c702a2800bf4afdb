#pragma once
// Signals arrive as readable data on a signalfd watched by the event loop: no code runs in signal
// context at all. block_daemon_signals() must run in main() before any thread starts, so that
// every thread inherits the mask.
#include <csignal>

namespace omega::daemon {

void block_daemon_signals();  // SIGTERM, SIGINT, SIGHUP blocked; SIGPIPE ignored

class SignalFd {
 public:
  SignalFd();  // throws std::system_error
  ~SignalFd();
  SignalFd(const SignalFd&) = delete;
  SignalFd& operator=(const SignalFd&) = delete;
  int fd() const { return fd_; }
  // Loop thread: the next pending signal number, or 0 when none is pending.
  int read_signal();

 private:
  int fd_ = -1;
};

}  // namespace omega::daemon
