#pragma once
// skinstream info FILE [--json]: what a capture holds and how much of it is missing.
#include <cstdio>
#include <string>

namespace skinstream::cli {

struct InfoOptions {
  std::string path;  // the capture (.c3d or .trc)
  bool json = false;
};

// Prints the summary (or its JSON) to `out`; returns the exit code. Throws on a file that
// cannot be read.
int run_info(const InfoOptions& options, std::FILE* out);

}  // namespace skinstream::cli
