#pragma once
// A program the bench runs as a child, without a shell (ip and tc for the shaped link, a
// skinstream-sub per joiner): what it printed, stdout and stderr together, and how it ended.

#include <chrono>
#include <string>
#include <vector>

namespace skinstream::bench {

struct CommandOptions {
  int nice = 0;                        // the child's nice level (0: the bench's own)
  bool idle = false;                   // the child under SCHED_IDLE: only CPU nothing else wants
  int stdin_fd = -1;                   // the child's standard input (-1: the bench's own)
  std::chrono::milliseconds limit{0};  // killed once it has run this long (0: no limit)
};

struct CommandResult {
  int exit_code = -1;  // -1: killed by a signal
  bool timed_out = false;
  std::string output;
};

// Runs argv[0] (searched in PATH when it has no '/'). Throws std::runtime_error when it cannot
// be started at all; a program that is not found exits 127 saying so.
CommandResult run_command(const std::vector<std::string>& argv, const CommandOptions& options = {});

}  // namespace skinstream::bench
