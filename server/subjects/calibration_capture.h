#pragma once
// A live calibration's range of motion: the next N frames of one subject's markers as the
// router gives them, copied on the io thread into room reserved when the calibration was asked
// for (nothing is allocated per frame; the room is only reserved, not written, so asking for 120 s
// of 350 markers, 120 MB, does not hold the io thread), then handed to the subject builder as a take.

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
  bool full() const { return filled_ == frames_wanted_; }
  int frames() const { return filled_; }
  int frames_wanted() const { return frames_wanted_; }
  // The frames so far, as a capture (the object is spent).
  Capture take();

 private:
  Capture capture_;  // its positions grow a frame at a time within their reserved room
  int frames_wanted_ = 0;
  int filled_ = 0;
};

}  // namespace skinstream::server
