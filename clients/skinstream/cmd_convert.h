#pragma once
// skinstream convert IN OUT: C3D <-> TRC, each format from its file's extension.
#include <cstdio>
#include <string>

namespace skinstream::cli {

struct ConvertOptions {
  std::string in_path, out_path;
};

// Writes OUT and one line saying so to `out`; returns the exit code. Throws on a file that
// cannot be read or written.
int run_convert(const ConvertOptions& options, std::FILE* out);

}  // namespace skinstream::cli
