// Flexing and breathing: bodybuilder poses held with tension, deep breaths between them.
#include <cmath>
#include <vector>

#include "core/synth/motion.h"

namespace skinstream::synth {

namespace {

std::vector<AngleKey> flex_keys(const Anatomy& anatomy) {
  const JointAngles rest = rest_angles(anatomy);
  JointAngles relaxed = rest;
  for (auto& arm : relaxed.arm) {
    arm.elevation = 20;
    arm.plane = 5;
    arm.elbow = 15;
  }
  JointAngles double_biceps = rest;  // upper arms sideways, forearms up, everything tense
  for (auto& arm : double_biceps.arm) {
    arm.plane = 10;
    arm.elevation = 95;
    arm.twist = -85;
    arm.elbow = 135;
    arm.wrist = 30;
    arm.clavicle_elevate = 8;
  }
  double_biceps.spine_flex = -6;
  double_biceps.effort = 1.0;
  JointAngles front = rest;  // "most muscular": arms down and forward, fists together, hunched
  for (auto& arm : front.arm) {
    arm.plane = 110;
    arm.elevation = 35;
    arm.twist = 40;
    arm.elbow = 100;
    arm.pronation = 40;
    arm.clavicle_protract = 18;
  }
  front.spine_flex = 15;
  front.neck_flex = -10;
  front.effort = 1.0;
  JointAngles curl = relaxed;  // one arm curls slowly to full flexion
  curl.arm[kRight].elbow = 145;
  curl.arm[kRight].plane = 80;
  curl.arm[kRight].elevation = 15;
  curl.effort = 0.6;

  std::vector<AngleKey> keys;
  keys.push_back({0.0, relaxed});
  keys.push_back({1.5, double_biceps});
  keys.push_back({3.5, double_biceps});
  keys.push_back({4.5, relaxed});
  keys.push_back({6.0, front});
  keys.push_back({7.8, front});
  keys.push_back({8.8, relaxed});
  keys.push_back({10.2, curl});
  keys.push_back({12.0, relaxed});
  return keys;
}

}  // namespace

JointAngles flex_motion(const Anatomy& anatomy, double t) {
  JointAngles a = interpolate_keys(flex_keys(anatomy), t, true);
  const double b = 0.5 * (1.0 - std::cos(2.0 * M_PI * t / 4.0));  // deep breaths, 4 s
  a.breath = b;
  a.spine_flex -= 3.0 * b;
  for (auto& arm : a.arm) arm.clavicle_elevate += 3.0 * b;
  // Tension pulses while posing (the subject "squeezes" the pose).
  a.effort *= 0.8 + 0.2 * std::sin(2.0 * M_PI * t / 1.3);
  return a;
}

}  // namespace skinstream::synth
