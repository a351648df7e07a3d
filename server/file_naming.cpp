#include "server/file_naming.h"

#include <cctype>
#include <ctime>

namespace skinstream::server {

std::string utc_text(std::chrono::system_clock::time_point when, const char* format) {
  const std::time_t t = std::chrono::system_clock::to_time_t(when);
  std::tm parts{};
  gmtime_r(&t, &parts);
  char text[64];
  std::strftime(text, sizeof text, format, &parts);
  return text;
}

std::string iso_utc(std::chrono::system_clock::time_point when) {
  return utc_text(when, "%Y-%m-%dT%H:%M:%SZ");
}

std::string file_stem_of(const std::string& name) {
  constexpr size_t kMaxBytes = 64;
  std::string stem;
  for (char c : name.substr(0, kMaxBytes))
    stem += std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.' ? c : '_';
  if (stem.empty() || stem.front() == '.') stem.insert(stem.begin(), 's');
  return stem;
}

}  // namespace skinstream::server
