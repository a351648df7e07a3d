#include "core/offline/rbf_ridge_selection.h"

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <random>

#include "core/deform/rbf_kernel.h"
#include "tests/core/deform/deform_test_support.h"

namespace skinstream {
namespace {

using deform_test::deform_non_rigidly;
using deform_test::random_motion;
using deform_test::random_points;

// The definition Rippa's formula shortcuts: fit eq. 7 (with the ridge) to every member but i,
// evaluate the fit at member i, and sum the squared misses.
double refit_without_each_member(const Eigen::Matrix3Xd& centres, const Eigen::MatrixX3d& residuals, double dilation,
                                 double ridge) {
  const int n = static_cast<int>(centres.cols());
  auto phi = [&](int a, int b) { return cubic_bspline_kernel((centres.col(a) - centres.col(b)).norm() / dilation); };
  double sum = 0.0;
  for (int left_out = 0; left_out < n; ++left_out) {
    std::vector<int> kept;
    for (int i = 0; i < n; ++i)
      if (i != left_out) kept.push_back(i);
    const int m = n - 1;
    Eigen::MatrixXd a(m, m);
    Eigen::MatrixX3d r(m, 3);
    for (int i = 0; i < m; ++i) {
      r.row(i) = residuals.row(kept[i]);
      for (int j = 0; j < m; ++j) a(i, j) = phi(kept[i], kept[j]) + (i == j ? ridge : 0.0);
    }
    const Eigen::MatrixX3d w = a.fullPivLu().solve(r);
    Eigen::RowVector3d fitted = Eigen::RowVector3d::Zero();
    for (int i = 0; i < m; ++i) fitted += phi(left_out, kept[i]) * w.row(i);
    sum += (residuals.row(left_out) - fitted).squaredNorm();
  }
  return sum;
}

TEST(RbfRidgeSelection, RippasFormulaEqualsRefittingWithoutEachMember) {
  std::mt19937_64 rng(41);
  const std::vector<Vec3> points = random_points(rng, 25, Vec3(80, 50, 30));
  Eigen::Matrix3Xd centres(3, 25);
  Eigen::MatrixX3d residuals(25, 3);
  std::normal_distribution<double> noise(0.0, 1.0);
  for (int i = 0; i < 25; ++i) {
    centres.col(i) = points[i];
    residuals.row(i) << std::sin(points[i].x() / 30.0) * 3.0 + noise(rng), noise(rng), std::cos(points[i].y() / 20.0);
  }
  const double dilation = 70.0;
  const std::vector<double> ridges{0.0, 1e-3, 0.05, 0.7};
  const std::vector<double> rippa = leave_one_out_squared_errors(centres, residuals, dilation, ridges);
  ASSERT_EQ(rippa.size(), ridges.size());
  for (size_t k = 0; k < ridges.size(); ++k) {
    const double direct = refit_without_each_member(centres, residuals, dilation, ridges[k]);
    EXPECT_NEAR(rippa[k], direct, 1e-7 * direct) << "ridge " << ridges[k];
  }
}

// A training take of one part: a smooth bulge under random rigid motions, plus independent
// noise per marker and frame of the given size.
std::vector<Vec3> part_take(const std::vector<Vec3>& members, int frames, double noise_mm, std::mt19937_64& rng) {
  std::normal_distribution<double> noise(0.0, noise_mm);
  std::vector<Vec3> take;
  for (int f = 0; f < frames; ++f)
    for (const Vec3& p : deform_non_rigidly(members, random_motion(rng)))
      take.push_back(p + Vec3(noise(rng), noise(rng), noise(rng)));
  return take;
}

TEST(RbfRidgeSelection, NoisyMarkersGetMoreSmoothingThanCleanOnes) {
  std::mt19937_64 rng(42);
  const std::vector<Vec3> members = random_points(rng, 60, Vec3(120, 60, 40));
  const PartModel part = build_part_model(members);
  std::vector<int> markers(members.size());
  for (size_t i = 0; i < markers.size(); ++i) markers[i] = static_cast<int>(i);
  const int frames = 20, count = static_cast<int>(members.size());

  const RidgeChoice clean = choose_rbf_ridge(part, markers, part_take(members, frames, 0.0, rng), frames, count);
  const RidgeChoice noisy = choose_rbf_ridge(part, markers, part_take(members, frames, 1.5, rng), frames, count);
  EXPECT_EQ(clean.frames, frames);
  EXPECT_GT(noisy.ridge, clean.ridge);
  EXPECT_GT(noisy.ridge, 0.0);
  // The chosen ridge misses the left-out markers by less than exact interpolation does, and
  // the noise (1.5 mm per axis) bounds the miss from below.
  EXPECT_LT(noisy.loo_rms_mm, noisy.loo_rms_exact_mm);
  EXPECT_GT(noisy.loo_rms_mm, 1.5);
  EXPECT_LE(clean.loo_rms_mm, clean.loo_rms_exact_mm);
}

TEST(RbfRidgeSelection, PartWithoutResidualTermKeepsNoRidgeAndBadTakesAreRejected) {
  const PartModel single = build_part_model({Vec3(1, 2, 3)});
  const std::vector<int> one{0};
  const RidgeChoice choice = choose_rbf_ridge(single, one, std::vector<Vec3>{Vec3(1, 2, 3)}, 1, 1);
  EXPECT_EQ(choice.ridge, 0.0);
  std::mt19937_64 rng(43);
  const std::vector<Vec3> members = random_points(rng, 12, Vec3(50, 40, 30));
  const PartModel part = build_part_model(members);
  std::vector<int> markers(12);
  for (int i = 0; i < 12; ++i) markers[i] = i;
  EXPECT_THROW(choose_rbf_ridge(part, markers, members, 2, 12), std::invalid_argument);  // one frame, not two
  EXPECT_THROW(choose_rbf_ridge(part, one, members, 1, 12), std::invalid_argument);      // wrong member list
  std::vector<Vec3> missing = members;
  missing[3] = Vec3::Constant(std::numeric_limits<double>::quiet_NaN());
  EXPECT_THROW(choose_rbf_ridge(part, markers, missing, 1, 12), std::invalid_argument);
}

}  // namespace
}  // namespace skinstream
