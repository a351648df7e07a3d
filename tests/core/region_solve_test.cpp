#include "core/region_solve.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>
#include <vector>

#include "core/region_pca_fit.h"
#include "support/allocation_counter.h"

namespace skinstream {
namespace {

constexpr int kMembers = 8;
constexpr int kModes = 4;

// A region's shape: a mean of kMembers points about 100 mm apart and kModes random modes of
// 5-20 mm, with 1 mm^2 residual.
struct RandomShape {
  RegionShapeGaussian shape;
  Eigen::MatrixXd modes;  // 3 * kMembers x kModes, scaled by their standard deviations
};

RandomShape random_shape(unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  RandomShape out;
  out.shape.mean.resize(3 * kMembers);
  for (int d = 0; d < 3 * kMembers; ++d) out.shape.mean(d) = 100.0 * normal(rng);
  out.modes.resize(3 * kMembers, kModes);
  for (int c = 0; c < kModes; ++c) {
    Eigen::VectorXd mode(3 * kMembers);
    for (int d = 0; d < 3 * kMembers; ++d) mode(d) = normal(rng);
    out.modes.col(c) = (20.0 - 5.0 * c) * mode.normalized() * std::sqrt(3.0 * kMembers);
  }
  out.shape.covariance = out.modes * out.modes.transpose() / (3.0 * kMembers);
  out.shape.residual_variance = 1.0;
  out.shape.calibration = 1.5;
  return out;
}

// Frame f of a take: the shape's mean moved by its modes and carried by a turning, moving rigid
// motion. Every member has a position (also the hidden ones: a solve must not read them).
std::vector<Vec3> pose(const RandomShape& s, int f) {
  Eigen::VectorXd c(kModes);
  for (int k = 0; k < kModes; ++k) c(k) = std::sin(0.05 * f * (k + 1) + k) / std::sqrt(3.0 * kMembers);
  const Eigen::VectorXd local = s.shape.mean + s.modes * c;
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(0.02 * f, Vec3(0.3, 0.5, 0.8).normalized()).toRotationMatrix();
  std::vector<Vec3> out(kMembers);
  for (int m = 0; m < kMembers; ++m) out[m] = turn * local.segment<3>(3 * m) + Vec3(2.0 * f, -f, 0.5 * f);
  return out;
}

// A solve kept across frames and remade only when the members seen or the shape change gives the
// answer of one made afresh every frame, over a take where the hidden set changes, stays, comes
// back to an earlier one and the shape changes under it. At each change the kept solve is stale,
// and the stale one's answer differs: the check can fail. Neither allocates.
TEST(RegionSolve, KeptSolveGivesTheFreshAnswerWhileTheHiddenSetChangesAndStays) {
  const RandomShape shapes[2] = {random_shape(3), random_shape(4)};
  struct Phase {
    int shape;
    std::vector<int> hidden;  // besides member 0
  };
  const std::vector<Phase> phases = {{0, {3}}, {0, {3, 5}}, {0, {3}}, {1, {3}}, {1, {}}, {1, {2, 6, 7}}};
  constexpr int kPhaseFrames = 40;
  std::vector<std::vector<Vec3>> poses;
  std::vector<std::vector<char>> seen;
  for (size_t p = 0; p < phases.size(); ++p)
    for (int f = 0; f < kPhaseFrames; ++f) {
      poses.push_back(pose(shapes[phases[p].shape], static_cast<int>(poses.size())));
      std::vector<char> observed(kMembers, 1);
      observed[0] = 0;
      for (int h : phases[p].hidden) observed[h] = 0;
      seen.push_back(observed);
    }

  RegionSolve kept;
  RegionPcaFit kept_fit, fresh_fit;
  int prepared = 0, stale_differs = 0, stale_checked = 0;
  test::CountAllocations counter;
  for (size_t f = 0; f < poses.size(); ++f) {
    const Phase& phase = phases[f / kPhaseFrames];
    const RegionShapeGaussian& shape = shapes[phase.shape].shape;
    Vec3 fresh;
    double fresh_variance = 0.0;
    ASSERT_TRUE(fresh_fit.estimate(shape, poses[f], seen[f], fresh, fresh_variance));
    const uint32_t mask = region_observed_mask(seen[f]);
    if (!kept.matches(mask, phase.shape)) {
      if (kept.observed_mask != 0) {
        Vec3 stale;
        double stale_variance = 0.0;
        kept_fit.estimate(kept, poses[f], stale, stale_variance);
        ++stale_checked;
        stale_differs += (stale - fresh).norm() > 1e-3 || std::abs(stale_variance - fresh_variance) > 1e-3 * fresh_variance;
      }
      ASSERT_TRUE(prepare_region_solve(shape, mask, phase.shape, kept));
      ++prepared;
    }
    Vec3 estimate;
    double variance = 0.0;
    kept_fit.estimate(kept, poses[f], estimate, variance);
    EXPECT_LT((estimate - fresh).norm(), 1e-9) << "frame " << f;
    EXPECT_NEAR(variance, fresh_variance, 1e-12 * fresh_variance) << "frame " << f;
  }
  EXPECT_EQ(counter.count(), 0u);
  EXPECT_EQ(prepared, static_cast<int>(phases.size()));
  EXPECT_EQ(stale_checked, static_cast<int>(phases.size()) - 1);
  EXPECT_EQ(stale_differs, stale_checked);
}

TEST(RegionSolve, NeedsThreeObservedMembers) {
  const RandomShape s = random_shape(5);
  std::vector<char> observed(kMembers, 0);
  observed[1] = observed[2] = 1;
  RegionSolve solve;
  EXPECT_FALSE(prepare_region_solve(s.shape, region_observed_mask(observed), 0, solve));
  EXPECT_EQ(solve.observed_mask, 0u);
  observed[4] = 1;
  EXPECT_TRUE(prepare_region_solve(s.shape, region_observed_mask(observed), 0, solve));
  EXPECT_EQ(solve.observed, 3);
  EXPECT_EQ(solve.hidden, kMembers - 3);
  EXPECT_EQ(solve.hidden_slots[0], 0);
  EXPECT_TRUE(solve.matches(region_observed_mask(observed), 0));
  // A failed prepare keeps nothing: no later mask matches it, not even that of no member seen.
  const std::vector<char> none(kMembers, 0);
  EXPECT_FALSE(prepare_region_solve(s.shape, region_observed_mask(none), 0, solve));
  EXPECT_FALSE(solve.matches(region_observed_mask(none), 0));
  EXPECT_FALSE(solve.matches(region_observed_mask(observed), 0));
}

}  // namespace
}  // namespace skinstream
