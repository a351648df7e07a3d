#include "server/subjects/calibration_capture.h"

#include <algorithm>

namespace skinstream::server {

CalibrationCapture::CalibrationCapture(std::vector<std::string> labels, int frames, double rate_hz)
    : capture_(std::move(labels), frames, rate_hz) {}

bool CalibrationCapture::add(const MarkerFrame& frame) {
  if (full()) return true;
  const size_t markers = std::min(frame.labelled.size(), static_cast<size_t>(capture_.point_count()));
  for (size_t m = 0; m < markers; ++m) capture_.at(filled_, static_cast<int>(m)) = frame.labelled[m];
  ++filled_;
  return full();
}

Capture CalibrationCapture::take() {
  Capture out = std::move(capture_);
  out.frame_count = filled_;
  out.positions.resize(static_cast<size_t>(filled_) * out.labels.size());
  return out;
}

}  // namespace skinstream::server
