#pragma once
// Does a training take move like a body? A person's markers change their distances to each other
// as the joints bend (a wrist to the opposite hip by hundreds of millimetres in any range of
// motion); the markers on a rigid object keep theirs, and so do an actor's who stands still.
// Neither can fit joints or teach the deformation models: the take is refused before the fit,
// with the figure that says why.

#include <span>
#include <string>

#include "core/capture.h"

namespace skinstream {

struct TakeMotionLimits {
  // The articulation (below) a take must reach. The shared real takes reach 178 mm (under two
  // seconds of a lab walk) to 928 mm (a long dance); an actor standing still reaches what sway,
  // breathing and noise give (a few mm), a rigid object its noise.
  double min_articulation_mm = 80.0;
  int max_frames = 400;  // frames sampled evenly over the take
};

struct TakeMotion {
  // Over every pair of markers seen together, how much their distance changes in the take
  // (max - min over the sampled frames); the articulation is the 75th percentile of those, so
  // that a few loose or swapped markers cannot make a rigid take move (one marker of 41 is in 5%
  // of the pairs), while a body moving its limbs moves most of its pairs.
  double articulation_mm = 0.0;
  int pairs = 0;
  std::string problem;  // empty: the take moves like a body
  bool ok() const { return problem.empty(); }
};

// frames: frame_count x markers positions (NaN: not seen).
TakeMotion measure_take_motion(std::span<const Vec3> frames, int frame_count, int markers, const TakeMotionLimits& limits = {});

}  // namespace skinstream
