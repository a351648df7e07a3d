#include "server/logging.h"

#include <spdlog/spdlog.h>

#include <stdexcept>

namespace skinstream::server {

void set_log_level(const std::string& level) {
  const spdlog::level::level_enum parsed = spdlog::level::from_str(level);
  if (parsed == spdlog::level::off && level != "off") throw std::invalid_argument("unknown log level \"" + level + "\"");
  spdlog::set_level(parsed);
}

bool RateLimitedLog::warn(std::string_view category, std::string_view detail) { return log(true, category, detail); }

bool RateLimitedLog::info(std::string_view category, std::string_view detail) { return log(false, category, detail); }

bool RateLimitedLog::log(bool warning, std::string_view category, std::string_view detail) {
  // A line that would not be printed at this level is not counted either (nor formatted).
  if (!spdlog::should_log(warning ? spdlog::level::warn : spdlog::level::info)) return false;
  const auto now = std::chrono::steady_clock::now();
  long suppressed = 0;
  {
    std::lock_guard lock(mutex_);
    auto it = entries_.find(category);
    if (it == entries_.end()) it = entries_.emplace(std::string(category), Entry{}).first;
    Entry& e = it->second;
    if (e.last != std::chrono::steady_clock::time_point{} && now - e.last < interval_) {
      ++e.suppressed;
      return false;
    }
    suppressed = e.suppressed;
    e.suppressed = 0;
    e.last = now;
  }
  const spdlog::level::level_enum level = warning ? spdlog::level::warn : spdlog::level::info;
  if (suppressed > 0)
    spdlog::log(level, "{}: {} ({} more like it in the last second)", category, detail, suppressed);
  else
    spdlog::log(level, "{}: {}", category, detail);
  return true;
}

}  // namespace skinstream::server
