// Several motions in one take, for a demo that shows more than one movement: punch, golf,
// jumprope, flex and breathe, each a fifth of the take at its natural speed, each blending into
// the next over 1 s (cosine-eased, from where the previous one would have gone on).
#include <algorithm>
#include <array>
#include <cmath>

#include "core/synth/motion.h"

namespace skinstream::synth {

JointAngles medley_motion(const Anatomy& anatomy, double t, double duration) {
  static constexpr std::array<const char*, 5> kPieces = {"punch", "golf", "jumprope", "flex", "breathe"};
  constexpr double kTransition = 1.0;  // s
  const double piece = std::max(duration, 1e-9) / kPieces.size();
  const size_t k = std::min(kPieces.size() - 1, static_cast<size_t>(std::max(t, 0.0) / piece));
  const double local = t - k * piece;
  const JointAngles current = motion_target_angles(kPieces[k], anatomy, local, piece);
  if (k == 0 || local >= kTransition) return current;
  const JointAngles previous = motion_target_angles(kPieces[k - 1], anatomy, local + piece, piece);
  return blend(previous, current, 0.5 - 0.5 * std::cos(M_PI * local / kTransition));
}

}  // namespace skinstream::synth
