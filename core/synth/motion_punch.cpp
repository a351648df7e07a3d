// Boxing: guard with the fists at the chin, a fast left jab and right cross (0.12 s out),
// bouncing on the knees. 1.2 s per jab-cross pair.
#include <cmath>
#include <vector>

#include "core/synth/motion.h"

namespace skinstream::synth {

namespace {

std::vector<AngleKey> punch_keys(const Anatomy& anatomy) {
  JointAngles guard = rest_angles(anatomy);
  guard.yaw = -15;
  guard.spine_flex = 8;
  guard.neck_flex = 5;
  for (int s = 0; s < 2; ++s) {
    guard.arm[s] = {0, 6, 60, 30, 30, 135, 60, 0};
    guard.leg[s].plane = 90;
    guard.leg[s].elevation = 15;
    guard.leg[s].knee = 25;
    guard.leg[s].ankle = 10;
  }
  guard.leg[kLeft].elevation = 25;  // left foot forward
  guard.leg[kRight].plane = -90;
  guard.leg[kRight].elevation = 5;
  guard.leg[kRight].ankle = 20;
  guard.leg[kLeft].twist = guard.yaw;
  guard.leg[kRight].twist = -guard.yaw;
  guard.effort = 0.3;

  JointAngles jab = guard;
  jab.yaw = -22;
  jab.spine_twist = -15;
  jab.arm[kLeft] = {0, 12, 100, 85, 10, 8, 90, 0};
  jab.effort = 1.0;

  JointAngles cross = guard;
  cross.yaw = 8;
  cross.spine_twist = 35;
  cross.arm[kRight] = {0, 12, 105, 85, 10, 8, 90, 0};
  cross.leg[kRight].ankle = -10;
  cross.leg[kRight].knee = 32;
  cross.leg[kRight].twist = 20;
  cross.effort = 1.0;

  return {{0.0, guard}, {0.12, jab}, {0.32, guard}, {0.6, guard}, {0.72, cross}, {0.95, guard}, {1.2, guard}};
}

}  // namespace

JointAngles punch_motion(const Anatomy& anatomy, double t) {
  JointAngles a = interpolate_keys(punch_keys(anatomy), t, true);
  const double bounce = std::sin(2.0 * M_PI * t / 0.6);
  for (auto& leg : a.leg) {
    leg.knee += 6.0 * bounce;
    leg.elevation += 3.0 * bounce;
    leg.ankle += 3.0 * bounce;
  }
  a.breath = tidal_breath(t, 3.0);
  return a;
}

}  // namespace skinstream::synth
