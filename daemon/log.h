#pragma once
// The daemon's log: one line per event on stderr (journald adds time and unit). Every refusal
// and every dropped connection names its cause here.
#include <fmt/format.h>

#include <atomic>
#include <mutex>
#include <string>
#include <string_view>

namespace omega::daemon {

enum class LogLevel { debug = 0, info = 1, warn = 2, error = 3 };
LogLevel parse_log_level(std::string_view s);  // throws std::invalid_argument

// Thread-safe: any thread may log; lines never interleave (mutex_ held while writing).
class Log {
 public:
  void set_level(LogLevel l) { level_.store(static_cast<int>(l)); }
  bool enabled(LogLevel l) const { return static_cast<int>(l) >= level_.load(); }

  template <class... A>
  void debug(fmt::format_string<A...> f, A&&... a) { write(LogLevel::debug, fmt::format(f, std::forward<A>(a)...)); }
  template <class... A>
  void info(fmt::format_string<A...> f, A&&... a) { write(LogLevel::info, fmt::format(f, std::forward<A>(a)...)); }
  template <class... A>
  void warn(fmt::format_string<A...> f, A&&... a) { write(LogLevel::warn, fmt::format(f, std::forward<A>(a)...)); }
  template <class... A>
  void error(fmt::format_string<A...> f, A&&... a) { write(LogLevel::error, fmt::format(f, std::forward<A>(a)...)); }

  void write(LogLevel l, const std::string& line);

 private:
  std::atomic<int> level_{static_cast<int>(LogLevel::info)};
  std::mutex mutex_;
};

}  // namespace omega::daemon
