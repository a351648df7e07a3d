#pragma once
// Seeded artificial occlusions for evaluating gap fillers: knock samples out of a capture whose
// truth is known, fill them, compare. The same seed gives the same gaps on every platform.

#include <cstdint>
#include <vector>

#include "core/capture.h"

namespace skinstream {

struct GapPlanOptions {
  uint64_t seed = 1;
  int min_frames = 3;                       // shortest gap
  double min_seconds = 0.0;                 // shortest gap in seconds too (the longer of the two)
  double max_seconds = 4.0;                 // longest gap, converted with the capture's rate
  double gaps_per_marker_per_minute = 6.0;  // expected count per labelled channel
  // When > 0, instead of a count per channel: gaps of `markers_per_gap` channels at once are
  // placed anywhere until this share of the labelled samples is missing (see below).
  double fraction_of_samples = 0.0;
  int markers_per_gap = 1;
  int margin_frames = 2;                    // present samples kept on each side of every gap
};

// The long-gap protocol: occlusions of 2 to 6 s, three markers at a time, until 4 % of the
// labelled samples are missing (a walking take's long occlusions, where drift shows).
GapPlanOptions long_gap_plan(uint64_t seed);

// Plans gaps on the labelled channels of `full`, a capture meant to have no gaps.
//   - Lengths are log-uniform between min_frames and L = max(min_frames, round(max_seconds * rate))
//     frames: length = floor(min_frames * ((L + 1) / min_frames)^u), u uniform in [0, 1), clamped
//     to L, so short and long occlusions are equally represented per octave.
//   - Per channel, the count is gaps_per_marker_per_minute * duration in minutes, rounded up or
//     down at random in proportion to the fraction (so its expectation is exact); each gap's
//     start is uniform over the positions where it fits. A gap that cannot be placed after 100
//     draws is dropped, so short captures may get fewer gaps.
//   - Every gap is interior: at least max(margin_frames, 1) present samples before it (so frame
//     0, the reference pose, is never covered) and margin_frames after it. On one channel, gaps
//     never overlap and keep margin_frames untouched samples between them. Samples already
//     missing in `full` are treated like planned gaps (a planned gap and its margins only cover
//     present samples), so a capture with a few real holes is usable too.
//   - Channels are independent, so several markers are often missing at the same time.
//   - With fraction_of_samples > 0 the gaps are not counted per channel: each draw is a length,
//     a start uniform over the capture and `markers_per_gap` channels chosen at random among
//     those where the gap fits (as above), all missing over the same frames. Draws go on until
//     the planned samples reach fraction_of_samples of all labelled samples, or 1000 draws in a
//     row find too few channels. The last gap may overshoot the share by one gap.
//   - Shortest length: max(min_frames, round(min_seconds * rate)).
// Randomness: std::mt19937_64 seeded with `seed`, converted to doubles by this code (not by
// std:: distributions, whose output differs between standard libraries).
// Returns the gaps sorted by point, then first_frame. Throws std::invalid_argument for
// min_frames < 1, negative min_seconds, max_seconds <= 0, negative rate of gaps or margin,
// fraction_of_samples outside [0, 0.5], markers_per_gap < 1, rate_hz <= 0, or positions that
// do not match labels x frame_count.
std::vector<Gap> plan_gaps(const Capture& full, const GapPlanOptions& options);

// A copy of `capture` with the samples of every gap set to missing. Throws std::invalid_argument
// for a gap with length < 1 or std::out_of_range for one outside the capture.
Capture apply_gaps(const Capture& capture, const std::vector<Gap>& gaps);

}  // namespace skinstream
