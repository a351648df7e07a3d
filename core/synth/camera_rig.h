#pragma once
// The optical stage: cameras around a small capture volume and the rule deciding whether a
// marker is reconstructed in a frame. Like Park & Hodgins' 12-camera Vicon stage (about 2 m x
// 2 m x 2.5 m): ten cameras high on a ring looking down and in, two low ones looking up to see
// markers that face the floor. A marker is seen by a camera when it is inside the camera's field
// of view, faces it (the angle between its normal and the direction to the camera is below the
// marker's visibility angle: a hemispherical marker on the skin is not seen edge-on) and the
// segment to the camera does not cross the body. It is reconstructed when at least
// `min_cameras` (two) see it.
#include <vector>

#include "core/geometry/triangle_bvh.h"
#include "core/synth/random.h"

namespace skinstream::synth {

struct Camera {
  Vec3 position = Vec3::Zero();  // mm
  Vec3 forward = Vec3::UnitY();  // unit optical axis
  double half_fov_deg = 40.0;    // half-angle of the (circular) field of view
};

struct VisibilityRule {
  double max_view_angle_deg = 80.0;  // between the marker normal and the direction to the camera
  // With a random source, detection fades from certain at grazing_start_deg to none at
  // max_view_angle_deg (a marker seen edge-on is a dim, squashed blob), and each detection is
  // also lost with camera_dropout (merged blobs, thresholding). Markers seen by few cameras
  // then flicker in and out as they do on a real stage.
  double grazing_start_deg = 75.0;
  double camera_dropout = 0.002;
  int min_cameras = 2;
  double skip_mm = 1.5;  // ignore the body closer than this to the marker along the ray
};

struct CameraRig {
  std::vector<Camera> cameras;

  // Ten cameras on a ring of `radius` mm at `high_mm`, aimed at a point `aim_high_mm` above the
  // centre, and two low ones at `low_mm` on opposite sides aimed up at `aim_low_mm`.
  static CameraRig stage12(const Vec3& centre = Vec3::Zero(), double radius = 2600.0, double high_mm = 2500.0,
                           double aim_high_mm = 850.0, double low_mm = 250.0, double aim_low_mm = 1150.0);
};

// Cameras that see the marker at p with outward normal n. Without a random source the rule is
// geometric only (every camera within max_view_angle_deg that has a clear line sees it).
int cameras_seeing(const CameraRig& rig, const TriangleBvh& body, const Vec3& p, const Vec3& n,
                   const VisibilityRule& rule = {}, Random* random = nullptr);
inline bool reconstructed(const CameraRig& rig, const TriangleBvh& body, const Vec3& p, const Vec3& n,
                          const VisibilityRule& rule = {}, Random* random = nullptr) {
  return cameras_seeing(rig, body, p, n, rule, random) >= rule.min_cameras;
}

}  // namespace skinstream::synth
