#pragma once
// The skinstream CLI run as a user would (its path from SKINSTREAM_CLI, which
// tests/clients/CMakeLists.txt sets for the CLI tests), and the bundled real captures the CLI tests read.
#include <string>

#include "support/program_run.h"
#include "support/test_data.h"

namespace skinstream::test {

inline ProgramRun run_cli(const std::string& arguments, bool stderr_too = true) {
  return run_program(std::string(SKINSTREAM_CLI) + " " + arguments, stderr_too);
}

// CMU subject 85, takes 02 and 12 (replay_data/cmu/, real captures).
inline const std::string kCmu02 = source_path("replay_data/cmu/85_02.c3d");
inline const std::string kCmu12 = source_path("replay_data/cmu/85_12.c3d");

}  // namespace skinstream::test
