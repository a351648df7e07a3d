#include "server/subjects/calibration_capture.h"

namespace skinstream::server {

CalibrationCapture::CalibrationCapture(std::vector<std::string> labels, int frames, double rate_hz)
    : capture_(std::move(labels), 0, rate_hz), frames_wanted_(frames) {
  capture_.positions.reserve(static_cast<size_t>(frames) * capture_.labels.size());
}

bool CalibrationCapture::add(const MarkerFrame& frame) {
  if (full()) return true;
  const size_t markers = static_cast<size_t>(capture_.point_count());
  for (size_t m = 0; m < markers; ++m)
    capture_.positions.push_back(m < frame.labelled.size() ? frame.labelled[m] : missing_point());
  ++filled_;
  capture_.frame_count = filled_;
  return full();
}

Capture CalibrationCapture::take() { return std::move(capture_); }

}  // namespace skinstream::server
