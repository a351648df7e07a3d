#include "protocol/files/capture_checks.h"

#include <cmath>

#include "protocol/files/file_error.h"

namespace skinstream {

void check_capture_shape(const Capture& capture, const std::string& path) {
  if (!(capture.rate_hz > 0.0) || !std::isfinite(capture.rate_hz))
    throw FileError(path, "cannot write frame rate " + std::to_string(capture.rate_hz) + " (must be positive)");
  if (capture.frame_count < 0) throw FileError(path, "negative frame count");
  if (capture.positions.size() != static_cast<size_t>(capture.frame_count) * capture.labels.size())
    throw FileError(path, "capture holds " + std::to_string(capture.positions.size()) + " positions for " +
                              std::to_string(capture.frame_count) + " frames x " +
                              std::to_string(capture.point_count()) + " points");
}

}  // namespace skinstream
