#pragma once
// The start of a C3D file (header block and parameter section) for a layout of points, shared
// by write_c3d and the take writer, which rewrites it with each new frame count: only values
// change with the count, never the size, so it can be written again in place.
#include <cstdint>
#include <string>
#include <vector>

#include "protocol/files/c3d.h"

namespace skinstream {

struct C3dPointLayout {
  const std::vector<std::string>& labels;
  double rate_hz = 0.0;
  int first_frame = 1;
  uint64_t frame_count = 0;
};

// Header and parameters, whole 512-byte blocks; the point data starts right after them.
// `scale` is POINT:SCALE (negative: float storage). Throws FileError naming `path`.
std::vector<uint8_t> c3d_preamble(const C3dPointLayout& layout, const std::string& path,
                                  const C3dWriteOptions& options, float scale);

}  // namespace skinstream
