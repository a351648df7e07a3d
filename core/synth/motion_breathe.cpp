// Standing quietly with deep, slow breathing: the chest rises, the belly moves out.
#include <cmath>

#include "core/synth/motion.h"

namespace skinstream::synth {

JointAngles breathe_motion(const Anatomy& anatomy, double t) {
  JointAngles a = rest_angles(anatomy);
  const double b = 0.5 * (1.0 - std::cos(2.0 * M_PI * t / 5.0));  // 5 s per breath, 0..1
  a.breath = b;
  for (int s = 0; s < 2; ++s) {
    a.arm[s].elevation = 22.0 + 3.0 * b;
    a.arm[s].plane = 5.0;
    a.arm[s].elbow = 20.0;
    a.arm[s].clavicle_elevate = 4.0 * b;
  }
  a.spine_flex = 2.0 - 5.0 * b;  // slight extension on inhalation
  a.neck_flex = 3.0 - 4.0 * b;
  return a;
}

}  // namespace skinstream::synth
