#pragma once
// Reads and writes captures, choosing the format by the file extension (.c3d or .trc).
#include <string>

#include "core/capture.h"

namespace skinstream {

Capture read_capture(const std::string& path);                   // throws FileError
void write_capture(const Capture& capture, const std::string& path);  // throws FileError

}  // namespace skinstream
