// Jumping rope: two-footed hops at 2.2 Hz, 0.25 s of free flight (about 75 mm high), landing
// and push-off through knees and ankles; elbows at the sides, wrists turning the rope.
#include <algorithm>
#include <cmath>

#include "core/synth/motion.h"

namespace skinstream::synth {

JointAngles jumprope_motion(const Anatomy& anatomy, double t) {
  constexpr double kHz = 2.2;
  constexpr double kFlight = 0.55;  // fraction of the hop in the air
  constexpr double kGravity = 9810.0;
  const double period = 1.0 / kHz;
  const double flight_time = kFlight * period;
  const double peak = kGravity * flight_time * flight_time / 8.0;

  JointAngles a = rest_angles(anatomy);
  const double phase = std::fmod(t * kHz, 1.0);
  double push = 0.0;  // 0..1 leg compression while on the ground
  if (phase < kFlight) {
    const double u = phase / kFlight;
    a.clearance = 4.0 * peak * u * (1.0 - u);
  } else {
    push = std::sin(M_PI * (phase - kFlight) / (1.0 - kFlight));
  }
  const double air = phase < kFlight ? std::sin(M_PI * phase / kFlight) : 0.0;
  for (int s = 0; s < 2; ++s) {
    a.leg[s].plane = 90;
    a.leg[s].elevation = 6.0 + 14.0 * push;
    a.leg[s].knee = 8.0 + 26.0 * push;
    a.leg[s].ankle = 2.0 + 16.0 * push - 22.0 * air;  // toes pointed in the air
    a.arm[s].plane = 25;
    a.arm[s].elevation = 18;
    a.arm[s].twist = 10;
    a.arm[s].elbow = 75;
    a.arm[s].pronation = 30;
  }
  // The rope turns once per hop: wrists circle (flexion and forearm rotation out of phase).
  const double rope = 2.0 * M_PI * kHz * t;
  for (int s = 0; s < 2; ++s) {
    a.arm[s].wrist = 20.0 * std::sin(rope);
    a.arm[s].pronation += 15.0 * std::cos(rope);
    a.arm[s].elevation += 4.0 * std::cos(rope);
  }
  a.spine_flex = 5.0 + 4.0 * push;
  a.neck_flex = -3.0 * push;
  a.breath = 0.5 * (1.0 - std::cos(2.0 * M_PI * t / 2.0)) * 0.7;
  a.effort = 0.2 + 0.5 * push;
  return a;
}

}  // namespace skinstream::synth
