#pragma once
// systemd integration: readiness, status, watchdog and socket activation. Every function is a
// no-op outside systemd (no $NOTIFY_SOCKET / $LISTEN_FDS).
#include <string>
#include <vector>

namespace omega::daemon {

// Loop thread.
void notify_ready(const std::string& status);
void notify_status(const std::string& status);
void notify_reloading();
void notify_stopping();
void notify_watchdog();
// The interval at which notify_watchdog() must be called (half of WatchdogSec), or 0 when the
// watchdog is off.
double watchdog_interval_s();

// Sockets passed by systemd (socket activation), already listening. Called once at start-up.
std::vector<int> activated_sockets();

}  // namespace omega::daemon
