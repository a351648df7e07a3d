#pragma once
// The names of this process's threads as `top -H` shows them (/proc/self/task/*/comm).

#include <filesystem>
#include <fstream>
#include <set>
#include <string>

namespace skinstream::test {

inline std::multiset<std::string> process_thread_names() {
  std::multiset<std::string> names;
  for (const auto& task : std::filesystem::directory_iterator("/proc/self/task")) {
    std::ifstream comm(task.path() / "comm");
    std::string name;
    if (std::getline(comm, name)) names.insert(name);
  }
  return names;
}

}  // namespace skinstream::test
