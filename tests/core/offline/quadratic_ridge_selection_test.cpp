#include "core/offline/quadratic_ridge_selection.h"

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <random>

#include "core/deform/part_deformation.h"
#include "core/deform/part_model.h"
#include "tests/core/deform/deform_test_support.h"

namespace skinstream {
namespace {

using deform_test::random_motion;
using deform_test::random_points;

std::vector<int> identity_markers(size_t count) {
  std::vector<int> markers(count);
  for (size_t i = 0; i < count; ++i) markers[i] = static_cast<int>(i);
  return markers;
}

// A take of one part: the members moved by a quadratic field (mm-scale bulges) under random
// rigid motions, plus independent noise per marker and frame.
std::vector<Vec3> quadratic_take(const std::vector<Vec3>& members, int frames, double noise_mm, std::mt19937_64& rng) {
  std::normal_distribution<double> noise(0.0, noise_mm), g;
  std::vector<Vec3> take;
  for (int f = 0; f < frames; ++f) {
    Eigen::Matrix<double, 3, 6> curvature;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 6; ++c) curvature(r, c) = 2e-4 * g(rng);  // ~2 mm at 100 mm
    const RigidTransform motion = random_motion(rng);
    for (const Vec3& p : members) {
      const QuadraticVector q = quadratic_basis(p);
      const Vec3 bulged = p + curvature * q.tail<6>() + Vec3(noise(rng), noise(rng), noise(rng));
      take.push_back(motion.apply(bulged));
    }
  }
  return take;
}

// The definition the hat-matrix formula shortcuts, for one frame: fit eq. 6's deviations with
// the ridge (in the part's scaled coordinates, per member as PartModel defines it) to every
// member but i, predict member i, and sum the squared misses.
double refit_without_each_member(const PartModel& part, const Eigen::Matrix3Xd& deviations, double ridge) {
  const int n = part.member_count();
  const double scale = std::sqrt(part.local_reference.colwise().squaredNorm().mean());
  Eigen::Matrix<double, 9, Eigen::Dynamic> scaled = part.quadratic_reference;
  scaled.topRows(3) /= scale;
  scaled.bottomRows(6) /= scale * scale;
  double sum = 0.0;
  for (int out = 0; out < n; ++out) {
    Eigen::Matrix<double, 9, 9> normal = Eigen::Matrix<double, 9, 9>::Zero();
    Eigen::Matrix<double, 3, 9> moments = Eigen::Matrix<double, 3, 9>::Zero();
    for (int i = 0; i < n; ++i) {
      if (i == out) continue;
      normal += scaled.col(i) * scaled.col(i).transpose();
      moments += deviations.col(i) * scaled.col(i).transpose();
    }
    normal.diagonal().tail<6>().array() += ridge * n;
    const Eigen::Matrix<double, 3, 9> coefficients = moments * normal.inverse();
    sum += (deviations.col(out) - coefficients * scaled.col(out)).squaredNorm();
  }
  return sum;
}

TEST(QuadraticRidgeSelection, LeaveOneOutMissEqualsRefittingWithoutEachMember) {
  std::mt19937_64 rng(51);
  const std::vector<Vec3> members = random_points(rng, 16, Vec3(100, 60, 40));
  const std::vector<Vec3> take = quadratic_take(members, 1, 1.0, rng);
  const PartModel exact = build_part_model(members);
  PartDeformer rigid(exact, DeformationMode::Rigid);
  ASSERT_TRUE(rigid.solve(take));
  const Eigen::Matrix3Xd deviations = rigid.local_positions() - exact.local_reference;
  for (double ridge : {0.0, 1e-3, 0.1, 10.0}) {
    const PartModel part = build_part_model(members, ridge);
    const Eigen::MatrixXd hat = part.pseudo_inverse * part.quadratic_reference;
    const Eigen::Matrix3Xd residual = deviations - deviations * hat;
    double shortcut = 0.0;
    for (int i = 0; i < part.member_count(); ++i)
      shortcut += residual.col(i).squaredNorm() / std::pow(1.0 - hat(i, i), 2);
    const double direct = refit_without_each_member(part, deviations, ridge);
    EXPECT_NEAR(shortcut, direct, 1e-6 * direct) << "ridge " << ridge;
  }
  // And the selection reports exactly that miss for the ridge it chose, over its one frame.
  const QuadraticRidgeChoice choice = choose_quadratic_ridge(members, identity_markers(members.size()), take, 1,
                                                             static_cast<int>(members.size()));
  const double direct = refit_without_each_member(build_part_model(members, choice.ridge), deviations, choice.ridge);
  EXPECT_NEAR(choice.loo_rms_mm, std::sqrt(direct / members.size()), 1e-6 * choice.loo_rms_mm);
}

// A take the paper's model fits exactly: in the part's frame every frame's deviation is a
// quadratic field whose mean over the members is zero (eq. 6's modes have no constant term,
// and the rigid fit would turn a mean into one), under random rigid motions.
std::vector<Vec3> take_in_the_models_span(const std::vector<Vec3>& members, int frames, std::mt19937_64& rng) {
  const PartModel part = build_part_model(members);
  Eigen::Matrix<double, 6, 1> mean = Eigen::Matrix<double, 6, 1>::Zero();
  for (const Vec3& p : part.local_reference_points) mean += quadratic_basis(p).tail<6>() / members.size();
  std::normal_distribution<double> g;
  std::vector<Vec3> take;
  for (int f = 0; f < frames; ++f) {
    Eigen::Matrix<double, 3, 6> curvature;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 6; ++c) curvature(r, c) = 2e-4 * g(rng);
    curvature -= (curvature * mean) * mean.transpose() / mean.squaredNorm();  // no mean deviation
    const RigidTransform motion = random_motion(rng);
    for (const Vec3& p : part.local_reference_points)
      take.push_back(motion.apply(part.reference_frame.apply_inverse(p + curvature * quadratic_basis(p).tail<6>())));
  }
  return take;
}

TEST(QuadraticRidgeSelection, ManyMembersOnAQuadraticFieldKeepThePapersFit) {
  std::mt19937_64 rng(52);
  const std::vector<Vec3> members = random_points(rng, 60, Vec3(120, 70, 50));
  const int frames = 12, count = static_cast<int>(members.size());
  const QuadraticRidgeChoice choice =
      choose_quadratic_ridge(members, identity_markers(members.size()), take_in_the_models_span(members, frames, rng), frames, count);
  EXPECT_EQ(choice.frames, frames);
  EXPECT_EQ(choice.ridge, 0.0);  // the exact fit predicts a left-out member of a quadratic field exactly
  EXPECT_LT(choice.loo_rms_mm, 1e-6);
}

TEST(QuadraticRidgeSelection, NineNoisyMembersGetARidge) {
  // Nine members: the paper's fit interpolates them (no member can be predicted), so with skin
  // noise the selection must draw the fit towards the linear modes.
  std::mt19937_64 rng(53);
  const std::vector<Vec3> members = random_points(rng, 9, Vec3(90, 60, 20));
  const int frames = 20;
  const QuadraticRidgeChoice choice =
      choose_quadratic_ridge(members, identity_markers(9), quadratic_take(members, frames, 1.5, rng), frames, 9);
  EXPECT_GT(choice.ridge, 0.0);
  EXPECT_TRUE(std::isinf(choice.loo_rms_exact_mm));
  EXPECT_TRUE(std::isfinite(choice.loo_rms_mm));
}

TEST(QuadraticRidgeSelection, SmallPartsGetNoneAndBadTakesAreRejected) {
  std::mt19937_64 rng(54);
  const std::vector<Vec3> few = random_points(rng, 6, Vec3(50, 40, 30));
  EXPECT_EQ(choose_quadratic_ridge(few, identity_markers(6), few, 1, 6).ridge, 0.0);
  const std::vector<Vec3> members = random_points(rng, 12, Vec3(50, 40, 30));
  const std::vector<int> markers = identity_markers(12);
  EXPECT_THROW(choose_quadratic_ridge(members, markers, members, 2, 12), std::invalid_argument);  // one frame, not two
  EXPECT_THROW(choose_quadratic_ridge(members, identity_markers(3), members, 1, 12), std::invalid_argument);
  std::vector<Vec3> missing = members;
  missing[3] = Vec3::Constant(std::numeric_limits<double>::quiet_NaN());
  EXPECT_THROW(choose_quadratic_ridge(members, markers, missing, 1, 12), std::invalid_argument);
}

}  // namespace
}  // namespace skinstream
