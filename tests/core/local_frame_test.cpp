#include "core/local_frame.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

namespace skinstream {
namespace {

TEST(LocalFrame, NoUsableNeighbourStillGivesARotation) {
  const Vec3 marker(1, 2, 3);
  const std::vector<Vec3> along_normal = {marker + Vec3(0, 0, 5)};
  const Eigen::Matrix3d r = local_reference_frame(marker, Vec3::UnitZ(), along_normal);
  EXPECT_NEAR(r.determinant(), 1.0, 1e-12);
  EXPECT_TRUE((r * r.transpose()).isIdentity(1e-12));
  EXPECT_TRUE(r.row(2).transpose().isApprox(Vec3::UnitZ()));
}

TEST(LocalFrame, AxesFollowEquationOne) {
  const Vec3 marker(10, 0, 0);
  const Vec3 normal = Vec3(1, 1, 0).normalized();
  // The first neighbour has a component along the normal; t is its tangential part.
  const std::vector<Vec3> ring = {marker + Vec3(0, 0, 40) + 7.0 * normal, marker + Vec3(30, -30, 0)};
  const Eigen::Matrix3d r = local_reference_frame(marker, normal, ring);
  EXPECT_TRUE(r.row(0).transpose().isApprox(Vec3::UnitZ(), 1e-12));           // t
  EXPECT_TRUE(r.row(2).transpose().isApprox(normal, 1e-12));                   // n
  EXPECT_TRUE(r.row(1).transpose().isApprox(normal.cross(Vec3::UnitZ()), 1e-12));  // b = n x t
  EXPECT_NEAR(r.determinant(), 1.0, 1e-12);
}

TEST(LocalFrame, LocalPositionsDoNotChangeUnderRigidMotion) {
  const Vec3 marker(0, 0, 0), normal(0, 0, 1);
  const std::vector<Vec3> ring = {Vec3(40, 5, 2), Vec3(-10, 38, -3), Vec3(-30, -30, 1)};
  const Eigen::Matrix3d r0 = local_reference_frame(marker, normal, ring);
  const Eigen::Matrix3d q = Eigen::AngleAxisd(0.9, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  const Vec3 shift(100, -50, 800);
  std::vector<Vec3> moved;
  for (const Vec3& p : ring) moved.push_back(q * p + shift);
  const Eigen::Matrix3d r1 = local_reference_frame(q * marker + shift, q * normal, moved);
  for (size_t k = 0; k < ring.size(); ++k)
    EXPECT_TRUE((r0 * (ring[k] - marker)).isApprox(r1 * (moved[k] - (q * marker + shift)), 1e-9));
}

}  // namespace
}  // namespace skinstream
