#pragma once
// A running process's cost, read from /proc: CPU seconds (user + system), resident set now and
// its peak.
#include <sys/types.h>

namespace skinstream::bench {

double cpu_seconds(pid_t pid);
long resident_kb(pid_t pid);       // VmRSS: sampled through a run to show whether memory stays flat
long peak_resident_kb(pid_t pid);  // VmHWM

}  // namespace skinstream::bench
