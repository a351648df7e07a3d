#include "core/absolute_orientation.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <random>

namespace skinstream {
namespace {

Eigen::Matrix3d random_rotation(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  return Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized().toRotationMatrix();
}

std::vector<Vec3> random_points(std::mt19937_64& rng, int count, double scale) {
  std::uniform_real_distribution<double> u(-scale, scale);
  std::vector<Vec3> p(count);
  for (Vec3& x : p) x = Vec3(u(rng), u(rng), u(rng));
  return p;
}

double residual(const RigidTransform& t, const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  double sum = 0;
  for (size_t k = 0; k < a.size(); ++k) sum += (t.apply(a[k]) - b[k]).squaredNorm();
  return sum;
}

// Independent reference: Kabsch/Umeyama by SVD with the reflection fix.
RigidTransform kabsch(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  Vec3 ca = Vec3::Zero(), cb = Vec3::Zero();
  for (size_t k = 0; k < a.size(); ++k) ca += a[k], cb += b[k];
  ca /= a.size();
  cb /= b.size();
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
  for (size_t k = 0; k < a.size(); ++k) h += (a[k] - ca) * (b[k] - cb).transpose();
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1 : 1;
  RigidTransform t;
  t.rotation = svd.matrixV() * d * svd.matrixU().transpose();
  t.translation = cb - t.rotation * ca;
  return t;
}

TEST(AbsoluteOrientation, EmptyInputGivesIdentityAndIsDegenerate) {
  RigidTransform t;
  t.translation = Vec3(1, 2, 3);
  const FitQuality q = fit_rigid({}, {}, t);
  EXPECT_TRUE(q.degenerate);
  EXPECT_EQ(q.points, 0);
  EXPECT_TRUE(t.rotation.isIdentity());
  EXPECT_TRUE(t.translation.isZero());
}

TEST(AbsoluteOrientation, RecoversRandomRigidMotionsExactly) {
  std::mt19937_64 rng(7);
  for (int trial = 0; trial < 200; ++trial) {
    const int count = 3 + trial % 12;
    const std::vector<Vec3> a = random_points(rng, count, 300.0);
    const Eigen::Matrix3d r = random_rotation(rng);
    const Vec3 d(trial * 3.0, -500.0, 1000.0);
    std::vector<Vec3> b;
    for (const Vec3& p : a) b.push_back(r * p + d);
    RigidTransform t;
    const FitQuality q = fit_rigid(a, b, t);
    EXPECT_FALSE(q.degenerate);
    EXPECT_LT((t.rotation - r).norm(), 1e-9) << "trial " << trial;
    EXPECT_LT((t.translation - d).norm(), 1e-6);
    EXPECT_NEAR(t.rotation.determinant(), 1.0, 1e-12);
  }
}

TEST(AbsoluteOrientation, NoisyFitMatchesSvdReference) {
  std::mt19937_64 rng(11);
  std::normal_distribution<double> noise(0.0, 2.0);
  for (int trial = 0; trial < 50; ++trial) {
    const std::vector<Vec3> a = random_points(rng, 8, 200.0);
    const Eigen::Matrix3d r = random_rotation(rng);
    std::vector<Vec3> b;
    for (const Vec3& p : a) b.push_back(r * p + Vec3(noise(rng), noise(rng), noise(rng)));
    RigidTransform t;
    fit_rigid(a, b, t);
    EXPECT_NEAR(residual(t, a, b), residual(kabsch(a, b), a, b), 1e-6);
  }
}

TEST(AbsoluteOrientation, ReflectedInputStillGivesBestProperRotation) {
  std::mt19937_64 rng(3);
  const std::vector<Vec3> a = random_points(rng, 10, 100.0);
  std::vector<Vec3> b;
  for (const Vec3& p : a) b.push_back(Vec3(-p.x(), p.y(), p.z()));  // a mirror image
  RigidTransform t;
  fit_rigid(a, b, t);
  EXPECT_NEAR(t.rotation.determinant(), 1.0, 1e-12);
  EXPECT_NEAR(residual(t, a, b), residual(kabsch(a, b), a, b), 1e-6);
}

TEST(AbsoluteOrientation, CollinearPointsAreDegenerateButStillMapped) {
  std::vector<Vec3> a = {Vec3(0, 0, 0), Vec3(10, 0, 0), Vec3(25, 0, 0)};
  std::mt19937_64 rng(5);
  const Eigen::Matrix3d r = random_rotation(rng);
  std::vector<Vec3> b;
  for (const Vec3& p : a) b.push_back(r * p + Vec3(5, 6, 7));
  RigidTransform t;
  const FitQuality q = fit_rigid(a, b, t);
  EXPECT_TRUE(q.degenerate);
  EXPECT_LT(residual(t, a, b), 1e-12);  // any rotation about the line fits; the points must land
}

TEST(AbsoluteOrientation, TwoPointsAreDegenerate) {
  std::vector<Vec3> a = {Vec3(0, 0, 0), Vec3(0, 10, 0)}, b = {Vec3(1, 1, 1), Vec3(1, 11, 1)};
  RigidTransform t;
  EXPECT_TRUE(fit_rigid(a, b, t).degenerate);
  EXPECT_LT(residual(t, a, b), 1e-12);
}

TEST(AbsoluteOrientation, RotationOnlyKeepsTheOrigin) {
  std::mt19937_64 rng(9);
  const std::vector<Vec3> a = random_points(rng, 5, 50.0);
  const Eigen::Matrix3d r = random_rotation(rng);
  std::vector<Vec3> b;
  for (const Vec3& p : a) b.push_back(r * p);
  Eigen::Matrix3d found;
  EXPECT_FALSE(fit_rotation(a, b, found).degenerate);
  EXPECT_LT((found - r).norm(), 1e-9);
}

}  // namespace
}  // namespace skinstream
