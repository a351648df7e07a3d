#pragma once
// Turns the true marker trajectories and their per-frame visibility into what an optical system
// delivers (Park & Hodgins section 4.2): trajectories broken into many partial ones.
//  - A marker's trajectory ends whenever it is occluded, and sometimes while visible: the
//    tracker loses it when its motion is hard to predict (high acceleration) or at random; a
//    tracking break loses a frame or two.
//  - The partial trajectory that includes the first frame keeps the marker's label. After a
//    gap the marker comes back as a new partial trajectory: recognised and labelled again with
//    some probability (likelier after a short gap), otherwise unlabelled ("*N" channel), and
//    now and then given the label of a neighbouring marker (a label swap: more likely when a
//    neighbour is close, as around a flexed elbow).
//  - A few ghost points (spurious reconstructions near real markers, a frame or two long).
//  - Every delivered sample gets sub-millimetre Gaussian noise.
#include <cstdint>
#include <vector>

#include "core/capture.h"
#include "core/synth/random.h"

namespace skinstream::synth {

// Defaults are calibrated so the generated takes resemble Park & Hodgins' Table 1 (partial
// trajectories, wrong-label rate and holes for flexing, golf, punching and jump rope).
struct BreakOptions {
  double noise_mm = 0.25;             // standard deviation per coordinate
  bool first_frame_complete = true;   // every marker labelled in frame 0 (the reference pose)
  double random_breaks_per_s = 0.03;  // per marker, while visible
  double predict_error_lo_mm = 1.0;   // constant-velocity prediction error where breaks begin
  double predict_error_hi_mm = 8.0;   // ... and where they reach break_max_probability per frame
  double break_max_probability = 0.2;
  double break_dropout_frames = 1.0;  // mean frames lost at a tracking break (0 with probability 0.4)
  int short_gap_frames = 6;
  double relabel_after_short_gap = 0.55;  // probability the tracker labels the returning marker again
  double relabel_after_long_gap = 0.2;
  double wrong_label = 0.004;       // probability a returning fragment gets a neighbour's label
  double wrong_label_close = 0.04;  // ... when a neighbour is within close_mm
  double close_mm = 30.0;
  double ghosts_per_s = 3.0;
  double ghost_frames = 2.0;      // mean length
  double ghost_offset_mm = 30.0;  // at most this far from the marker it shadows
  double ghost_noise_mm = 1.0;
};

struct BreakCounts {
  int trajectories = 0;           // partial trajectories (runs of one source in one channel), ghosts included
  int labelled_fragments = 0;     // runs in labelled channels (correct or not)
  int unlabelled_fragments = 0;   // runs of real markers in "*N" channels
  int wrong_label_fragments = 0;  // runs in a labelled channel that belong to another marker
  int ghost_trajectories = 0;
  int ghost_samples = 0;
  long holes = 0;                 // marker-frames not delivered in any channel
  int gaps = 0;                   // runs of such marker-frames
  double missing_fraction = 0.0;  // of labelled channels' samples (what a labelled-only reader sees)
};

struct BrokenCapture {
  Capture capture;          // labelled channels first (marker order), then "*0", "*1", ...
  std::vector<int> source;  // frame-major like Capture::positions: true marker, -1 ghost, -2 no sample
  BreakCounts counts;

  int source_at(int frame, int channel) const {
    return source[static_cast<size_t>(frame) * capture.labels.size() + static_cast<size_t>(channel)];
  }
};

// truth: every labelled marker at every frame; visible: frame-major (frame * markers + marker);
// neighbours: for each marker, markers near it on the skin. Throws std::invalid_argument when
// the sizes disagree or the truth has missing samples.
BrokenCapture break_trajectories(const Capture& truth, const std::vector<uint8_t>& visible,
                                 const std::vector<std::vector<int>>& neighbours, const BreakOptions& options,
                                 Random& rng);

// The counts of a broken capture from its source map (also used by tests).
BreakCounts count_breaks(const Capture& capture, const std::vector<int>& source, int markers);

}  // namespace skinstream::synth
