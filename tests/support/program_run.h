#pragma once
// Runs one of the project's real programs as a user would, from a shell command line, and
// collects what it printed and how it exited.
#include <string>

namespace skinstream::test {

struct ProgramRun {
  int exit_code;       // -1 when it did not exit normally (a signal)
  std::string output;  // stdout, and stderr unless it was left out
};

// stderr_too: false leaves the program's stderr on the test's own (in ctest's log), so that
// `output` is stdout alone (a JSON report, say).
ProgramRun run_program(const std::string& command_line, bool stderr_too = true);

}  // namespace skinstream::test
