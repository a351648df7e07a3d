#pragma once
// Runs one of skinstream's commands in-process, as main would after parsing, and keeps what it
// printed; and parses a command line given as words.
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>
#include <vector>

#include "clients/skinstream/command_line.h"

namespace skinstream::test {

struct CommandOutput {
  int exit_code;
  std::string text;  // what the command printed to its output (not stderr)
};

template <typename Options>
CommandOutput run_command(int (*run)(const Options&, std::FILE*), const Options& options) {
  struct Memory {
    char* bytes = nullptr;
    size_t size = 0;
    std::FILE* file = open_memstream(&bytes, &size);
    ~Memory() {
      if (file) std::fclose(file);
      std::free(bytes);
    }
  } memory;
  const int exit_code = run(options, memory.file);
  std::fclose(memory.file);
  memory.file = nullptr;
  return {exit_code, std::string(memory.bytes, memory.size)};
}

// `skinstream WORDS...` parsed into `out` (see parse_command_line).
inline std::optional<int> parse_words(const std::vector<std::string>& words, cli::CommandLine& out) {
  std::vector<const char*> argv = {"skinstream"};
  for (const std::string& w : words) argv.push_back(w.c_str());
  return cli::parse_command_line(static_cast<int>(argv.size()), argv.data(), out);
}

}  // namespace skinstream::test
