#pragma once
// The bounded lookahead stage. With a lookahead of L frames, every frame is released L frames
// after it arrived; when a marker reappears, the frames of its gap still held here are pulled
// towards the measurement: the jump between the last estimate and the new measurement, in the
// marker's local frame (eq. 2), is spread back over them, full next to the measurement and
// fading linearly. It also takes back the relabels the filler revoked within its window
// (GapFillerOptions::confirm_frames = L). Costs L frames of latency (L / rate seconds). L = 0
// passes frames through.

#include <span>
#include <vector>

#include "core/gap_filler.h"
#include "core/subject_model.h"

namespace skinstream {

class GapEndBlender {
 public:
  GapEndBlender(const SubjectModel& model, int lookahead);

  int lookahead() const { return lookahead_; }

  // Adds the newest filled frame; when a frame is due, writes it (and its number) and returns true.
  // `revoked` (empty, or one per marker: FrameOutput::revoked from the filler): the relabels of
  // that many frames before this one, still held here, are given back as estimates.
  bool push(std::span<const Vec3> positions, std::span<const MarkerStatus> status, long frame_number,
            const FrameOutput& out, long& out_frame_number, std::span<const int> revoked = {});
  // At the end of a take: releases the frames still held, oldest first, one per call.
  bool drain(const FrameOutput& out, long& out_frame_number);
  void reset() { held_ = 0; }

 private:
  int slot(int age) const;  // age 0 = newest
  void blend_gap_end(int marker);
  void give_back(int marker, int frames);
  std::span<const Vec3> frame(int age) const;

  const SubjectModel& model_;
  int lookahead_;
  int n_;
  int capacity_;
  int newest_ = -1;
  int held_ = 0;
  std::vector<Vec3> positions_;          // capacity x n
  std::vector<MarkerStatus> status_;     // capacity x n
  std::vector<long> frame_numbers_;
};

}  // namespace skinstream
