#pragma once
// A running process's cost, read from /proc: CPU seconds (user + system), resident set now and
// its peak. For the benchmark and the end-to-end tests, which watch the daemon they started.
#include <sys/types.h>

#include <map>
#include <string>

namespace skinstream::server {

double cpu_seconds(pid_t pid);
// CPU seconds (user + system) in the text of a /proc/PID/stat or /proc/PID/task/TID/stat.
double cpu_seconds_of_stat(const std::string& text);
// CPU seconds (user + system) of each of a process's threads, summed by thread name.
std::map<std::string, double> thread_cpu_seconds(pid_t pid);
long resident_kb(pid_t pid);       // VmRSS: sampled through a run to show whether memory stays flat
long peak_resident_kb(pid_t pid);  // VmHWM

}  // namespace skinstream::server
