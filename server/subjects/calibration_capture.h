#pragma once
// A live calibration's range of motion: the next N frames of one subject's markers as the
// router gives them, copied on the io thread into a capture sized when the calibration was
// asked for (nothing is allocated per frame), then handed to the subject builder as a take.

#include <string>
#include <vector>

#include "core/capture.h"
#include "server/ingest/marker_frame.h"

namespace skinstream::server {

class CalibrationCapture {
 public:
  // `labels`: the subject's markers, in its order (MarkerFrame::labelled).
  CalibrationCapture(std::vector<std::string> labels, int frames, double rate_hz);

  // The io thread: copies the frame's labelled markers (missing stay missing). True once full.
  bool add(const MarkerFrame& frame);
  bool full() const { return filled_ == capture_.frame_count; }
  int frames() const { return filled_; }
  int frames_wanted() const { return capture_.frame_count; }
  // The frames so far, as a capture (the object is spent).
  Capture take();

 private:
  Capture capture_;
  int filled_ = 0;
};

}  // namespace skinstream::server
