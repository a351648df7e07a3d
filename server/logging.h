#pragma once
// Logging for the daemon (spdlog), and a limiter so a flood of one kind of bad input (a broken
// sender at 120 Hz), or of connections (hundreds of subscribers at once), logs once a second
// with a count instead of a line each.

#include <chrono>
#include <map>
#include <mutex>
#include <string>
#include <string_view>

namespace skinstream::server {

// Sets spdlog's level from a name (trace ... off); throws std::invalid_argument otherwise.
void set_log_level(const std::string& level);

class RateLimitedLog {
 public:
  explicit RateLimitedLog(std::chrono::milliseconds interval = std::chrono::seconds(1)) : interval_(interval) {}
  // Logs a warning for `category` unless one was logged less than `interval` ago; the next one
  // that is logged says how many were suppressed. Returns whether it logged.
  bool warn(std::string_view category, std::string_view detail);
  // The same at level info (what each subscriber's connection says).
  bool info(std::string_view category, std::string_view detail);

 private:
  bool log(bool warning, std::string_view category, std::string_view detail);

  struct Entry {
    std::chrono::steady_clock::time_point last{};
    long suppressed = 0;
  };
  std::chrono::milliseconds interval_;
  std::mutex mutex_;
  std::map<std::string, Entry, std::less<>> entries_;
};

}  // namespace skinstream::server
