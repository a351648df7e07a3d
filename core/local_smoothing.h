#pragma once
// Smoothing in the local frame (section 4.4): a marker's trajectory is expressed relative to its
// one-ring (the eq. 2 transform, local reference frame -> world), smoothed there with repeated
// x <- x - lambda * D4 x (D4 the fourth difference in time), and brought back to the world.
// Filtering the local trajectory removes noise without eating into the body's rigid motion.
//
// Per iteration a frequency w is scaled by 1 - 16 lambda sin^4(w/2): with the defaults
// (lambda 0.05, 10 iterations) at 120 Hz, 10 Hz loses 3%, 30 Hz 89%, 60 Hz everything.
//
// Offline: the whole capture at once, no latency. Online: a sliding window of `past` frames,
// the frame released, and `lookahead` frames after it; latency = lookahead / rate. With
// lookahead 0 the window is one-sided and the smoothing lags slightly behind fast changes.

#include <span>
#include <vector>

#include "core/gap_filler.h"
#include "core/subject_model.h"

namespace skinstream {

struct SmoothingOptions {
  double lambda = 0.05;  // stable below 1/8
  int iterations = 10;
  int past = 8;          // online window: frames before the released one
  int lookahead = 2;     // online window: frames after it (latency)
};

// `positions`: frames x markers, complete (filled). Smoothed in place.
void smooth_offline(const SubjectModel& model, std::vector<Vec3>& positions, int frames, const SmoothingOptions& options);

class OnlineSmoother {
 public:
  OnlineSmoother(const SubjectModel& model, const SmoothingOptions& options);

  // Adds a complete frame; once `lookahead` newer frames have arrived, writes the smoothed
  // frame (with its number and status) and returns true. Allocation-free.
  bool push(std::span<const Vec3> positions, std::span<const MarkerStatus> status, long frame_number,
            const FrameOutput& out, long& out_frame_number);
  bool drain(const FrameOutput& out, long& out_frame_number);  // end of take: the held frames
  void reset() { count_ = pending_ = 0; }

 private:
  bool release(int age, const FrameOutput& out, long& out_frame_number);
  int slot(int age) const;

  const SubjectModel& model_;
  SmoothingOptions options_;
  int n_;
  int capacity_;
  int newest_ = -1;
  int count_ = 0;
  int pending_ = 0;  // pushed, not yet released
  std::vector<Vec3> local_;                 // capacity x n, local coordinates
  std::vector<RigidTransform> transforms_;  // capacity x n
  std::vector<char> has_transform_;
  std::vector<Vec3> world_;
  std::vector<MarkerStatus> status_;
  std::vector<long> frame_numbers_;
  std::vector<Vec3> window_, scratch_;
};

}  // namespace skinstream
