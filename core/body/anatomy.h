#pragma once
// Anatomical roles of the bones of a MakeHuman-style skeleton and a pose builder that speaks in
// joint angles (degrees) instead of quaternions. Bone names follow MakeHuman's default
// skeleton (spine05..spine01, neck01..03, head, clavicle.L, upperarm01.R, lowerleg01.L...);
// a role whose bone is absent is -1 and its rotations are ignored.
//
// Body axes (see skeleton.h): +X = subject's right, +Y = forward, +Z = up.
#include <array>
#include <string>
#include <vector>

#include "core/body/body.h"
#include "core/body/skeleton.h"

namespace skinstream {

enum Side { kLeft = 0, kRight = 1 };
inline const char* side_suffix(Side s) { return s == kLeft ? "L" : "R"; }
inline double lateral_sign(Side s) { return s == kLeft ? -1.0 : 1.0; }  // lateral direction is sign * +X

inline const Vec3 kAxisRight{1.0, 0.0, 0.0};
inline const Vec3 kAxisForward{0.0, 1.0, 0.0};
inline const Vec3 kAxisUp{0.0, 0.0, 1.0};

struct ArmBones {
  int clavicle = -1, shoulder = -1, upperarm = -1, upperarm_twist = -1, elbow = -1, forearm_twist = -1,
      wrist = -1;
};
struct LegBones {
  int pelvis = -1, hip = -1, thigh_twist = -1, knee = -1, shank_twist = -1, ankle = -1;
};

struct Anatomy {
  int root = -1;
  std::array<int, 5> spine{-1, -1, -1, -1, -1};  // spine05 (lowest) .. spine01
  std::array<int, 3> neck{-1, -1, -1};           // neck01 .. neck03
  int head = -1;
  std::array<ArmBones, 2> arm;
  std::array<LegBones, 2> leg;

  Vec3 hip_centre = Vec3::Zero();  // pivot of whole-body rotations
  std::array<Vec3, 2> shoulder_joint, elbow_joint, wrist_joint, hip_joint, knee_joint, ankle_joint;
  std::array<Vec3, 2> upperarm_dir, forearm_dir, thigh_dir, shank_dir;  // rest, unit
  std::array<Vec3, 2> elbow_axis;  // rest; rotating the forearm by +angle about it flexes the elbow
  std::array<double, 2> elbow_rest_flex{0.0, 0.0};  // radians the rest pose is already flexed
  std::array<std::vector<Vec3>, 2> sole_points;     // rest heel and ball of each foot (on the ankle bone)

  // Throws std::invalid_argument when the skeleton lacks the bones every motion needs
  // (spine, both upper arms, forearms, thighs and shanks).
  static Anatomy from(const Body& body);
};

// Builds a Pose by composing joint rotations in anatomical terms. Angles in degrees.
class PoseBuilder {
 public:
  PoseBuilder(const Skeleton& skeleton, const Anatomy& anatomy);

  // Premultiplies the local rotation of `bone` (no-op for bone < 0).
  void rotate(int bone, const Vec3& axis, double degrees);

  void spine(double flex, double side_bend,
             double twist);  // flex: forward; side: toward the right; twist: chest to the left
  void neck(double flex, double side_bend, double twist);
  // Arm elevation from hanging straight down, in the vertical plane at `plane` degrees from the
  // lateral direction toward the front (0 = abduction, 90 = forward flexion, > 90 across the
  // body, < 0 behind), then `twist` about the arm (positive = internal rotation). Replaces the
  // rest A-pose direction of the upper arm.
  void shoulder(Side s, double plane, double elevation, double twist = 0.0);
  void clavicle(Side s, double elevate, double protract);
  void elbow(Side s, double flex);  // absolute flexion, 0 = straight arm
  void forearm_twist(Side s, double pronation);
  void wrist(Side s, double flex);
  // Thigh elevation as for the shoulder: plane 90 = hip flexion, 0 = abduction, -90 = extension.
  void hip(Side s, double plane, double elevation, double twist = 0.0);
  void knee(Side s, double flex);
  void ankle(Side s, double dorsiflex);
  // Whole body: translation (mm), then yaw (to the left), pitch (forward) and roll (to the
  // right) about the hip centre.
  void body(const Vec3& translation, double yaw, double pitch, double roll);

  const Pose& pose() const { return pose_; }

 private:
  void swing(int bone, const Vec3& rest_dir, const Vec3& target_dir, double twist);
  const Skeleton& skeleton_;
  const Anatomy& anatomy_;
  Pose pose_;
};

// Vertical offset that puts the lowest sole point of the posed skeleton at `clearance` mm.
double ground_offset(const Anatomy& anatomy, const BoneTransforms& bones, double clearance);

}  // namespace skinstream
