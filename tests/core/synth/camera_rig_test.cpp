#include "core/synth/camera_rig.h"

#include <gtest/gtest.h>

namespace skinstream::synth {
namespace {

// A box "torso": 300 wide (x), 200 deep (y), 600 tall, centred at (0, 0, 1000), faces outward.
TriangleBvh torso() {
  const double x = 150, y = 100, z0 = 700, z1 = 1300;
  const std::vector<Vec3> p = {{-x, -y, z0}, {x, -y, z0}, {x, y, z0}, {-x, y, z0},
                               {-x, -y, z1}, {x, -y, z1}, {x, y, z1}, {-x, y, z1}};
  const std::vector<Face> q = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4},
                               {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
  return TriangleBvh(p, triangulate(q));
}

CameraRig front_cameras(int n) {
  CameraRig rig;
  for (int i = 0; i < n; ++i) {
    Camera c;
    c.position = Vec3(-1000.0 + 2000.0 * i / std::max(1, n - 1), 2500, 2000);
    c.forward = (Vec3(0, 0, 1000) - c.position).normalized();
    rig.cameras.push_back(c);
  }
  return rig;
}

TEST(SynthVisibility, NoCamerasSeesNothing) {
  const TriangleBvh body = torso();
  EXPECT_EQ(cameras_seeing(CameraRig{}, body, Vec3(0, 104, 1000), Vec3::UnitY()), 0);
  EXPECT_FALSE(reconstructed(CameraRig{}, body, Vec3(0, 104, 1000), Vec3::UnitY()));
}

TEST(SynthVisibility, StageHasTenHighCamerasLookingDownAndTwoLowLookingUp) {
  const CameraRig rig = CameraRig::stage12();
  ASSERT_EQ(rig.cameras.size(), 12u);
  int high = 0, low = 0;
  for (const Camera& c : rig.cameras) {
    if (c.position.z() > 2000 && c.forward.z() < 0) ++high;
    if (c.position.z() < 500 && c.forward.z() > 0) ++low;
  }
  EXPECT_EQ(high, 10);
  EXPECT_EQ(low, 2);
}

TEST(SynthVisibility, ChestMarkerFacingTheCamerasIsReconstructed) {
  const TriangleBvh body = torso();
  const CameraRig rig = CameraRig::stage12();
  const Vec3 chest(0, 104, 1100);
  EXPECT_GE(cameras_seeing(rig, body, chest, Vec3::UnitY()), 3);
  EXPECT_TRUE(reconstructed(rig, body, chest, Vec3::UnitY()));
}

TEST(SynthVisibility, MarkerHiddenBehindTheTorsoIsMissing) {
  const CameraRig rig = front_cameras(6);
  // Behind the back, facing forward (toward the cameras): only the torso is in the way.
  const Vec3 behind(0, -140, 1000);
  EXPECT_EQ(cameras_seeing(rig, torso(), behind, Vec3::UnitY()), 0);
  EXPECT_FALSE(reconstructed(rig, torso(), behind, Vec3::UnitY()));
  EXPECT_EQ(cameras_seeing(rig, TriangleBvh({}, {}), behind, Vec3::UnitY()), 6);  // no body: all see it
}

TEST(SynthVisibility, MarkerFacingAwayIsNotSeenAndOneCameraIsNotEnough) {
  const TriangleBvh body = torso();
  const Vec3 front(0, 104, 1000);
  EXPECT_EQ(cameras_seeing(front_cameras(6), body, front, -Vec3::UnitY()), 0);  // faces away
  EXPECT_EQ(cameras_seeing(front_cameras(1), body, front, Vec3::UnitY()), 1);
  EXPECT_FALSE(reconstructed(front_cameras(1), body, front, Vec3::UnitY()));
  EXPECT_TRUE(reconstructed(front_cameras(2), body, front, Vec3::UnitY()));
  VisibilityRule one;
  one.min_cameras = 1;
  EXPECT_TRUE(reconstructed(front_cameras(1), body, front, Vec3::UnitY(), one));
}

TEST(SynthVisibility, OnlyTheLowCamerasSeeAMarkerFacingTheFloor) {
  const TriangleBvh body = torso();
  const CameraRig rig = CameraRig::stage12();
  const Vec3 under(0, 0, 696);  // under the box, facing down
  EXPECT_EQ(cameras_seeing(rig, body, under, -Vec3::UnitZ()), 2);
}

TEST(SynthVisibility, RandomDetectionOnlyLosesMarkers) {
  const TriangleBvh body = torso();
  const CameraRig rig = CameraRig::stage12();
  VisibilityRule rule;
  rule.camera_dropout = 0.2;
  Random r(3);
  for (const Vec3& n : {Vec3(0, 1, 0), Vec3(0.7, 0.7, 0.1).normalized(), Vec3(0, 0.3, 1).normalized()}) {
    const Vec3 p = Vec3(0, 100, 1000) + 4.0 * n;
    const int sure = cameras_seeing(rig, body, p, n, rule);
    for (int i = 0; i < 50; ++i) EXPECT_LE(cameras_seeing(rig, body, p, n, rule, &r), sure);
  }
  VisibilityRule exact;
  exact.camera_dropout = 0.0;
  exact.grazing_start_deg = exact.max_view_angle_deg;
  const Vec3 n = Vec3(0.6, 0.8, 0).normalized();
  EXPECT_EQ(cameras_seeing(rig, body, Vec3(0, 104, 1000), n, exact, &r),
            cameras_seeing(rig, body, Vec3(0, 104, 1000), n, exact));
}

}  // namespace
}  // namespace skinstream::synth
