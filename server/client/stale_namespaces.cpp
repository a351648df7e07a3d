#include "server/client/stale_namespaces.h"

#include <signal.h>

#include <cerrno>
#include <charconv>
#include <filesystem>

namespace skinstream::server {

std::vector<std::string> namespaces_of_dead_processes(std::string_view prefix, const std::string& netns_dir) {
  std::vector<std::string> dead;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(netns_dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) continue;
    long pid = 0;
    const char* digits = name.data() + prefix.size();
    const auto [end, error] = std::from_chars(digits, name.data() + name.size(), pid);
    if (error != std::errc() || end == digits || pid <= 0) continue;
    // ESRCH: no such process. EPERM means it runs under another user: not ours to judge.
    if (kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH) dead.push_back(name);
  }
  return dead;
}

}  // namespace skinstream::server
