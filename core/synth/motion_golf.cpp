// A golf-like swing for a right-handed player: address, backswing, fast downswing (0.3 s),
// follow-through to a high finish and back to address. 4.2 s per swing.
#include <vector>

#include "core/synth/motion.h"

namespace skinstream::synth {

namespace {

// Legs for a trunk pitched forward by `pitch`: thighs `thigh_tilt` forward of vertical, knees
// flexed, feet flat; hips twisted to keep the feet pointing forward when the body yaws.
void golf_legs(JointAngles& a, double pitch, double thigh_tilt, double knee_left, double knee_right) {
  const double knee[2] = {knee_left, knee_right};
  for (int s = 0; s < 2; ++s) {
    a.leg[s].plane = 90;
    a.leg[s].elevation = pitch + thigh_tilt;
    a.leg[s].knee = knee[s];
    a.leg[s].ankle = knee[s] - thigh_tilt;  // shank tilt cancelled: foot flat
  }
  a.leg[kLeft].twist = a.yaw;
  a.leg[kRight].twist = -a.yaw;
}

std::vector<AngleKey> golf_keys(const Anatomy& anatomy) {
  const JointAngles rest = rest_angles(anatomy);

  JointAngles address = rest;
  address.pitch = 30;
  address.spine_flex = 10;
  address.neck_flex = 15;
  golf_legs(address, 30, 15, 20, 20);
  for (auto& arm : address.arm) {
    arm.plane = 115;
    arm.elevation = 40;
    arm.twist = 10;
    arm.wrist = 10;
  }
  address.arm[kLeft].elbow = 5;
  address.arm[kRight].elbow = 18;
  address.effort = 0.2;

  JointAngles top = address;
  top.yaw = -25;
  top.spine_twist = -50;
  top.spine_flex = 5;
  top.neck_twist = 40;  // eyes stay on the ball
  golf_legs(top, 30, 15, 28, 16);
  top.arm[kLeft] = {0, 10, 150, 95, 20, 8, 0, 40};
  top.arm[kRight] = {0, 0, 60, 90, -60, 95, 0, 40};
  top.effort = 0.4;

  JointAngles impact = address;
  impact.yaw = 15;
  impact.spine_twist = 15;
  impact.neck_twist = -10;
  golf_legs(impact, 30, 15, 10, 32);
  impact.leg[kRight].ankle = -10;
  impact.arm[kLeft].elbow = 2;
  impact.arm[kRight].elbow = 10;
  impact.effort = 1.0;

  JointAngles finish = rest;
  finish.pitch = 8;
  finish.yaw = 40;
  finish.spine_twist = 45;
  finish.spine_flex = -5;
  finish.neck_twist = -30;
  golf_legs(finish, 8, 5, 10, 35);
  finish.leg[kRight].ankle = -35;
  finish.arm[kRight] = {0, 10, 150, 110, 10, 30, 0, 20};
  finish.arm[kLeft] = {0, 5, 40, 100, -60, 110, 0, 30};
  finish.effort = 0.3;

  return {{0.0, address}, {0.5, address}, {1.5, top},    {1.7, top},
          {2.0, impact},  {2.45, finish}, {3.2, finish}, {4.2, address}};
}

}  // namespace

JointAngles golf_motion(const Anatomy& anatomy, double t) {
  JointAngles a = interpolate_keys(golf_keys(anatomy), t, true);
  a.breath = tidal_breath(t, 4.2);
  return a;
}

}  // namespace skinstream::synth
