#include "support/program_run.h"

#include <array>
#include <cstdio>
#include <sys/wait.h>

namespace skinstream::test {

ProgramRun run_program(const std::string& command_line, bool stderr_too) {
  FILE* pipe = popen((command_line + (stderr_too ? " 2>&1" : "")).c_str(), "r");
  if (!pipe) return {-1, "popen failed: " + command_line};
  std::string output;
  std::array<char, 4096> buffer;
  while (size_t n = fread(buffer.data(), 1, buffer.size(), pipe)) output.append(buffer.data(), n);
  const int status = pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, output};
}

}  // namespace skinstream::test
