#pragma once
// Constants of the C3D format (c3d.org) that the reader and the writer share.
#include <cstddef>
#include <cstdint>

namespace skinstream::c3d_format {

constexpr size_t kBlockBytes = 512;   // a C3D file is addressed in blocks of 512 bytes
constexpr uint8_t kHeaderKey = 0x50;  // the header's second byte in every C3D file

}  // namespace skinstream::c3d_format
