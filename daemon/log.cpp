#include "daemon/log.h"

#include <cstdio>
#include <stdexcept>

namespace omega::daemon {

LogLevel parse_log_level(std::string_view s) {
  if (s == "debug") return LogLevel::debug;
  if (s == "info") return LogLevel::info;
  if (s == "warn" || s == "warning") return LogLevel::warn;
  if (s == "error") return LogLevel::error;
  throw std::invalid_argument("log_level: expected debug, info, warn or error, got '" + std::string(s) + "'");
}

void Log::write(LogLevel l, const std::string& line) {
  if (!enabled(l)) return;
  // sd-daemon(3) priority prefixes: journald maps them to levels, a terminal shows them as-is.
  static constexpr const char* kPrefix[] = {"<7>debug: ", "<6>", "<4>warning: ", "<3>error: "};
  std::lock_guard lock(mutex_);
  std::fprintf(stderr, "%s%s\n", kPrefix[static_cast<int>(l)], line.c_str());
  std::fflush(stderr);
}

}  // namespace omega::daemon
