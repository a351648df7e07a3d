#pragma once
// Which CPUs the deform threads (the pipeline thread, then each worker) run on.
//
// Left to itself, the scheduler of a small virtual machine kept the pipeline thread and its
// worker on one core for about one frame in five (it packs threads so that other cores can
// idle), and those frames were deformed by one thread: skinstream-bench showed deformation
// p90 1.2 ms unpinned against 0.75 ms pinned, on the same code, and in four 10-minute runs
// with both cores of a 2-core machine pinned the processing p99 was 1.6-2.0 ms against
// 2.2-2.5 ms in three unpinned ones. One pinned run dropped 9 frames, which the mailbox's
// wait limit now absorbs when they come as a burst. So `auto` (the default) pins whenever
// there is a CPU per thread, `off` never does, and a list names the CPUs.

#include <string>
#include <thread>
#include <vector>

namespace skinstream::server {

// Checks the form of a deform_cpus setting: "auto", "off", or CPU numbers separated by
// commas. Returns the problem, or an empty string.
std::string deform_cpus_problem(const std::string& spec);

// The CPU for each of `threads` deform threads (index 0: the pipeline thread), or none.
// `allowed`: the CPUs this process may run on, ascending.
//  - "auto": the last `threads` allowed CPUs (CPU 0 tends to take the most interrupts), or
//    none when fewer are allowed than there are threads;
//  - "off": none;
//  - a list: exactly `threads` distinct CPUs, each of them allowed.
// Throws std::invalid_argument, saying what is wrong, for a list that does not fit.
std::vector<int> choose_deform_cpus(const std::string& spec, int threads, const std::vector<int>& allowed);

// The CPUs the calling process may run on (its affinity mask), ascending.
std::vector<int> allowed_cpus();

// Lets a thread run on `cpus` only (one CPU pins it); false when the OS refuses or a number
// is out of range.
bool set_thread_cpus(std::thread& thread, const std::vector<int>& cpus);
bool set_this_thread_cpus(const std::vector<int>& cpus);
inline bool pin_this_thread(int cpu) { return set_this_thread_cpus({cpu}); }

}  // namespace skinstream::server
