#pragma once
// C3D motion capture files (c3d.org): 3D points only; analog channels are skipped on read
// and never written. Positions come back in millimetres whatever POINT:UNITS says.
#include <cstdint>
#include <span>
#include <string>

#include "core/capture.h"

namespace skinstream {

// The byte order / float format of a C3D file, named after the machines that defined them.
enum class C3dProcessor {
  Intel,  // little-endian, IEEE floats (processor byte 84)
  Dec,    // little-endian, VAX F floats (85)
  Mips,   // big-endian, IEEE floats (86; SGI)
};

struct C3dWriteOptions {
  C3dProcessor processor = C3dProcessor::Intel;
  // Float storage keeps every float-representable coordinate exactly; integer storage (half
  // the size) rounds to a scale chosen from the data, so each coordinate is within scale / 2.
  bool float_storage = true;
};

// Missing samples (negative residual, NaN or exactly (0,0,0)) come back as missing_point().
Capture read_c3d(const std::string& path);  // throws FileError
// The same from a whole file's bytes in memory; `name` stands for the path in errors.
Capture read_c3d_bytes(std::span<const uint8_t> bytes, const std::string& name);
void write_c3d(const Capture& capture, const std::string& path,
               const C3dWriteOptions& options = {});  // throws FileError

}  // namespace skinstream
