#pragma once
// skinstream fill: run the online gap filler over a capture, exactly as the daemon would.
#include <cstdio>
#include <string>

#include "core/capture_filler.h"

namespace skinstream::cli {

struct FillOptions {
  std::string subject_path;  // subject file from build-subject
  std::string in_path;       // capture with gaps
  std::string out_path;      // filled capture to write
  CaptureFillOptions fill;
};

// Writes the filled capture and prints what was done as JSON to `out`; returns the exit code.
// Throws on bad files or a subject none of whose markers the capture has.
int run_fill(const FillOptions& options, std::FILE* out);

}  // namespace skinstream::cli
