// Range of motion: every major joint through its range, from the reference pose and back.
#include <algorithm>

#include "core/synth/motion.h"

namespace skinstream::synth {

namespace {

constexpr double kNatural = 20.0;  // s at natural speed

std::vector<AngleKey> rom_keys(const Anatomy& anatomy) {
  const JointAngles rest = rest_angles(anatomy);
  std::vector<AngleKey> keys;
  auto add = [&](double t, const JointAngles& a) { keys.push_back({t, a}); };
  auto both_arms = [](JointAngles& a, double plane, double elevation, double twist, double elbow) {
    for (int s = 0; s < 2; ++s) {
      a.arm[s].plane = plane;
      a.arm[s].elevation = elevation;
      a.arm[s].twist = twist;
      a.arm[s].elbow = elbow;
    }
  };
  add(0.0, rest);

  JointAngles a = rest;  // arms forward, head turns left
  both_arms(a, 90, 90, 0, 5);
  a.neck_twist = 60;
  add(1.2, a);

  a = rest;  // arms overhead, head back
  both_arms(a, 60, 170, 0, 5);
  a.neck_flex = -35;
  a.spine_flex = -10;
  for (auto& arm : a.arm) arm.clavicle_elevate = 15;
  add(2.4, a);

  a = rest;  // arms sideways above horizontal: armpits open, head turns right
  both_arms(a, 0, 105, -20, 5);
  a.neck_twist = -60;
  add(3.6, a);

  a = rest;  // double biceps: upper arms horizontal, elbows flexed up
  both_arms(a, 10, 90, -85, 130);
  a.effort = 0.7;
  add(4.8, a);

  a = rest;  // arms pressed to the sides, elbows flexed: armpits closed, head down
  both_arms(a, 20, 6, 30, 125);
  a.neck_flex = 40;
  for (auto& arm : a.arm) arm.pronation = 60;
  add(6.0, a);

  a = rest;  // arms crossed in front (horizontal adduction)
  both_arms(a, 150, 90, 0, 30);
  for (auto& arm : a.arm) arm.clavicle_protract = 15;
  add(7.2, a);

  add(8.0, rest);

  a = rest;  // forward bow, arms hanging
  a.spine_flex = 55;
  a.pitch = 25;
  a.neck_flex = 20;
  for (auto& leg : a.leg) {  // the legs stay vertical while the pelvis tips forward
    leg.plane = 90;
    leg.elevation = 25;
  }
  both_arms(a, 90, 75, 0, 15);
  add(9.2, a);

  a = rest;  // side bend right, then left
  a.spine_side = 30;
  a.neck_side = 15;
  a.arm[kLeft].elevation = 120;
  add(10.2, a);
  a = rest;
  a.spine_side = -30;
  a.neck_side = -15;
  a.arm[kRight].elevation = 120;
  add(11.2, a);

  a = rest;  // twist left then right, arms folded forward
  a.spine_twist = 45;
  a.neck_twist = 20;
  both_arms(a, 120, 80, 0, 110);
  add(12.2, a);
  a.spine_twist = -45;
  a.neck_twist = -20;
  add(13.2, a);

  add(13.8, rest);

  a = rest;  // right knee lift
  a.leg[kRight].elevation = 95;
  a.leg[kRight].knee = 100;
  a.leg[kRight].ankle = -20;
  a.arm[kLeft].elevation = 60;
  a.arm[kRight].elevation = 60;
  add(14.8, a);
  a = rest;  // left knee lift
  a.leg[kLeft].elevation = 95;
  a.leg[kLeft].knee = 100;
  a.leg[kLeft].ankle = -20;
  a.arm[kLeft].elevation = 60;
  a.arm[kRight].elevation = 60;
  add(15.8, a);

  a = rest;  // deep crouch, arms forward: belly and inner thighs hidden
  a.pitch = 35;
  a.spine_flex = 25;
  a.neck_flex = -20;
  for (int s = 0; s < 2; ++s) {
    a.leg[s].plane = 85;
    a.leg[s].elevation = 85;
    a.leg[s].twist = -10;
    a.leg[s].knee = 125;
    a.leg[s].ankle = 5;
  }
  both_arms(a, 90, 80, 0, 20);
  a.effort = 0.5;
  add(17.3, a);

  a = rest;  // right leg sideways
  a.leg[kRight].plane = 0;
  a.leg[kRight].elevation = 40;
  a.roll = -8;
  add(18.2, a);
  a = rest;  // left leg sideways
  a.leg[kLeft].plane = 0;
  a.leg[kLeft].elevation = 40;
  a.roll = 8;
  add(19.1, a);
  add(kNatural, rest);
  return keys;
}

}  // namespace

JointAngles rom_motion(const Anatomy& anatomy, double t, double duration) {
  const double speed = duration > 0.0 ? std::max(1.0, kNatural / duration) : 1.0;
  JointAngles a = interpolate_keys(rom_keys(anatomy), t * speed, true);
  a.breath = tidal_breath(t);
  return a;
}

}  // namespace skinstream::synth
