#pragma once
// Checks shared by every capture writer before anything is written.
#include <string>

#include "core/capture.h"

namespace skinstream {

// Throws FileError(path, ...) for a non-positive rate or positions that do not match
// frames x points.
void check_capture_shape(const Capture& capture, const std::string& path);

}  // namespace skinstream
