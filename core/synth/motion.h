#pragma once
// Procedural motions for the synthetic capture, in joint angles (degrees) on a MakeHuman-style
// skeleton. Every motion starts in the rest (reference) pose, as the subjects of Park & Hodgins
// did, and blends into its movement during the first 0.8 s.
//
//   rom       range of motion: neck, shoulders (flexion, overhead, abduction), elbows, trunk
//             bend/side bend/twist, hips (knee lifts, abduction), a deep crouch. Time-scaled to
//             the take: 20 s plays it at natural speed, shorter takes play it faster.
//   breathe   standing, deep slow breathing (5 s period)
//   flex      bodybuilder poses (double biceps, front flex) with deep breathing, 12 s cycle
//   golf      address, backswing, fast downswing, follow-through, 4.2 s cycle
//   punch     boxing guard with alternating jab and cross, 1.2 s cycle
//   jumprope  hopping at 2.2 Hz with turning wrists: flight, landing impacts
//   medley    punch, golf, jumprope, flex and breathe in turn, each a fifth of the take, each
//             blending into the next over 1 s (the demo: several motions in one take)
//   static    the rest pose with quiet breathing (for tests)
#include <string>
#include <vector>

#include "core/body/anatomy.h"

namespace skinstream::synth {

// The pose in joint angles. Defaults are "no rotation"; rest_angles() gives the rest pose.
struct JointAngles {
  double spine_flex = 0, spine_side = 0, spine_twist = 0;
  double neck_flex = 0, neck_side = 0, neck_twist = 0;
  struct Arm {
    double clavicle_elevate = 0, clavicle_protract = 0;
    double plane = 0, elevation = 0, twist = 0;  // PoseBuilder::shoulder (absolute)
    double elbow = 0, pronation = 0, wrist = 0;  // elbow absolute flexion
  };
  struct Leg {
    double plane = 90, elevation = 0, twist = 0;  // PoseBuilder::hip (relative to rest)
    double knee = 0, ankle = 0;
  };
  Arm arm[2];
  Leg leg[2];
  Vec3 translation = Vec3::Zero();  // horizontal body translation, mm (vertical comes from grounding)
  double yaw = 0, pitch = 0, roll = 0;
  double clearance = 0;  // height of the lowest sole point above the floor, mm
  double breath = 0;     // 0 = exhaled, 1 = deep inhalation
  double effort = 0;     // voluntary muscle tension 0..1 (adds to muscle bulge)
};

JointAngles rest_angles(const Anatomy& anatomy);
JointAngles blend(const JointAngles& a, const JointAngles& b, double w);  // (1-w) a + w b
Pose build_pose(const Skeleton& skeleton, const Anatomy& anatomy, const JointAngles& angles);

struct MotionSample {
  Pose pose;            // grounded
  double breath = 0.0;  // 0..1
  double effort = 0.0;  // 0..1
};

const std::vector<std::string>& motion_names();
bool is_motion(const std::string& name);

// The angles of motion `name` at time t (s) of a take lasting `duration` s, before grounding.
// Throws std::invalid_argument for an unknown motion.
JointAngles motion_angles(const std::string& name, const Anatomy& anatomy, double t, double duration);
// The same without the blend in from the rest pose at the start of the take.
JointAngles motion_target_angles(const std::string& name, const Anatomy& anatomy, double t, double duration);

// motion_angles posed and grounded (soles on the floor, or `clearance` above it).
MotionSample sample_motion(const std::string& name, const Skeleton& skeleton, const Anatomy& anatomy,
                           double t, double duration);

// Keyframed angles: smooth (cosine-eased) interpolation between consecutive keys; before the
// first key the first, after the last the last, unless `loop` wraps t into [first, last).
struct AngleKey {
  double time;
  JointAngles angles;
};
JointAngles interpolate_keys(const std::vector<AngleKey>& keys, double t, bool loop);

// The individual motions (one file each).
JointAngles rom_motion(const Anatomy& anatomy, double t, double duration);
JointAngles breathe_motion(const Anatomy& anatomy, double t);
JointAngles flex_motion(const Anatomy& anatomy, double t);
JointAngles golf_motion(const Anatomy& anatomy, double t);
JointAngles punch_motion(const Anatomy& anatomy, double t);
JointAngles jumprope_motion(const Anatomy& anatomy, double t);
JointAngles medley_motion(const Anatomy& anatomy, double t, double duration);

// Quiet breathing (0..0.45) with the given period, for motions that do not breathe deeply.
double tidal_breath(double t, double period_s = 4.0);

}  // namespace skinstream::synth
