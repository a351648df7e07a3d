// A process's cost read from /proc, as the benchmark and the end-to-end tests read the daemon's:
// the stat line parsed past a command name that holds spaces and parentheses, and this test's
// own process seen to use CPU and memory.
#include "server/client/process_usage.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>

namespace skinstream::server {
namespace {

TEST(ProcessUsage, StatTextGivesUserPlusSystemTime) {
  const double tick = 1.0 / static_cast<double>(sysconf(_SC_CLK_TCK));
  // Fields 14 and 15 (utime, stime) are 250 and 50 ticks; the name "(a) b)" would shift a reader
  // that split at the first ')'.
  const std::string stat = "4242 ((a) b)) S 1 4242 4242 0 -1 4194560 100 0 0 0 250 50 0 0 20 0 3 0 1000 0 0";
  EXPECT_DOUBLE_EQ(cpu_seconds_of_stat(stat), 300 * tick);
  EXPECT_EQ(cpu_seconds_of_stat("4242 (cut"), 0.0);
  EXPECT_EQ(cpu_seconds_of_stat(""), 0.0);
}

TEST(ProcessUsage, ThisProcessUsesCpuAndMemory) {
  const double before = cpu_seconds(getpid());
  // Busy for a quarter of a second of wall time: at least a few clock ticks of CPU.
  volatile double sink = 0;
  for (const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(250); std::chrono::steady_clock::now() < end;)
    sink = sink + 1.0;
  EXPECT_GT(cpu_seconds(getpid()), before);
  EXPECT_GT(resident_kb(getpid()), 0);
  EXPECT_GE(peak_resident_kb(getpid()), resident_kb(getpid()));
  double threads = 0;
  for (const auto& [name, seconds] : thread_cpu_seconds(getpid())) threads += seconds;
  EXPECT_GT(threads, 0.0);
  EXPECT_LE(threads, cpu_seconds(getpid()) + 0.05);
}

}  // namespace
}  // namespace skinstream::server
