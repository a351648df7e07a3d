#pragma once
// Network namespaces a benchmark or a test made and could not remove, because it was killed (a
// sanitizer's abort, a timeout, Ctrl-C) before its destructor ran. They are named after the
// process that made them (PREFIX + pid, then anything), so the next run can tell them: a name
// whose process is gone is left over, and removing it takes its veth pairs and bridge with it.
#include <string>
#include <string_view>
#include <vector>

namespace skinstream::server {

// The names in `netns_dir` (`ip netns`'s folder) that start with `prefix` and a process id no
// longer running.
std::vector<std::string> namespaces_of_dead_processes(std::string_view prefix, const std::string& netns_dir = "/var/run/netns");

}  // namespace skinstream::server
