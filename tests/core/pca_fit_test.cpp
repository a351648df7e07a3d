#include "core/pca_fit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace skinstream {
namespace {

// A 3-member ring whose members move along one shared direction: one component.
MarkerPcaModel one_mode_model() {
  MarkerPcaModel m;
  m.mean = Eigen::VectorXd::Zero(9);
  m.mean << 10, 0, 0, 0, 10, 0, -10, -10, 0;
  m.basis = Eigen::MatrixXd::Zero(9, 1);
  m.basis << 1, 0, 0, 0, 1, 0, -1, -1, 0;
  m.basis.normalize();
  m.variance = Eigen::VectorXd::Constant(1, 100.0);
  m.residual_variance = 0.01;
  m.slot_calibration = Eigen::VectorXd::Ones(3);
  m.rigid_variance = 1.0;
  return m;
}

TEST(PcaFit, ReconstructsAMissingMemberFromTheOthers) {
  const MarkerPcaModel m = one_mode_model();
  const double c = 7.0;
  const Eigen::VectorXd truth = m.mean + m.basis.col(0) * c;
  const std::vector<int> slots = {0, 1};  // member 2 missing
  const std::vector<Vec3> local = {truth.segment<3>(0), truth.segment<3>(3)};
  PcaFit fit;
  ASSERT_TRUE(fit.fit(m, slots, local));
  // The prior shrinks exactly by s / (s + residual / variance), s = |observed basis rows|^2.
  const double s = m.basis.topRows(6).squaredNorm();
  EXPECT_NEAR(fit.coefficients()(0), c * s / (s + m.residual_variance / m.variance(0)), 1e-12);
  EXPECT_LT((fit.reconstruct(m, 2) - truth.segment<3>(6)).norm(), 1e-2);
}

TEST(PcaFit, PriorKeepsCoefficientsBoundedWhenLittleIsObserved) {
  MarkerPcaModel m = one_mode_model();
  m.residual_variance = 100.0;  // observations as uncertain as the prior
  const std::vector<int> slots = {0};
  const std::vector<Vec3> local = {Vec3(10 + 1000, 0, 0)};  // an absurd observation
  PcaFit fit;
  ASSERT_TRUE(fit.fit(m, slots, local));
  // Unregularised least squares would give ~1730; the prior shrinks it by half at least.
  EXPECT_LT(std::abs(fit.coefficients()(0)), 0.6 * 1000.0 * std::sqrt(3.0));
}

TEST(PcaFit, PredictiveVarianceGrowsWhenLessIsObserved) {
  const MarkerPcaModel m = one_mode_model();
  PcaFit both, one;
  const std::vector<int> two_slots = {0, 1}, one_slot = {0};
  const std::vector<Vec3> two_local = {m.mean.segment<3>(0), m.mean.segment<3>(3)}, one_local = {m.mean.segment<3>(0)};
  ASSERT_TRUE(both.fit(m, two_slots, two_local));
  ASSERT_TRUE(one.fit(m, one_slot, one_local));
  EXPECT_GE(both.predictive_variance(m, 2), m.residual_variance);
  EXPECT_GT(one.predictive_variance(m, 2), both.predictive_variance(m, 2));
}

// The factored fit is the same fit: one factor per set of observed slots serves every frame
// that sees that set, whatever the positions.
TEST(PcaFit, FactoredFitMatchesTheDirectFitForEveryObservation) {
  MarkerPcaModel m;
  m.mean = Eigen::VectorXd::LinSpaced(12, -30.0, 25.0);
  m.basis = Eigen::MatrixXd(12, 2);
  for (int r = 0; r < 12; ++r) m.basis.row(r) << std::sin(0.7 * r + 0.3), std::cos(1.3 * r);
  m.basis.col(0).normalize();
  m.basis.col(1) -= m.basis.col(0) * m.basis.col(0).dot(m.basis.col(1));
  m.basis.col(1).normalize();
  m.variance = Eigen::VectorXd(2);
  m.variance << 400.0, 25.0;
  m.residual_variance = 2.0;
  m.slot_calibration = Eigen::VectorXd::Ones(4);
  m.rigid_variance = 1.0;
  const std::vector<int> slots = {0, 2};  // members 1 and 3 missing
  std::vector<double> factor(4);
  ASSERT_TRUE(PcaFit::factor_slots(m, slots, factor));
  for (double c : {-12.0, 0.5, 31.0}) {
    const std::vector<Vec3> local = {m.mean.segment<3>(0) + m.basis.block<3, 1>(0, 0) * c + Vec3(1, -2, 0.5),
                                     m.mean.segment<3>(6) + m.basis.block<3, 1>(6, 1) * (0.3 * c)};
    PcaFit direct, factored;
    ASSERT_TRUE(direct.fit(m, slots, local));
    factored.fit_factored(m, slots, local, factor);
    EXPECT_LT((factored.coefficients() - direct.coefficients()).norm(), 1e-9 * (1.0 + direct.coefficients().norm()));
    EXPECT_LT((factored.reconstruct(m, 3) - direct.reconstruct(m, 3)).norm(), 1e-9);
  }
}

TEST(PcaFit, ModelWithoutComponentsIsItsMean) {
  MarkerPcaModel m = one_mode_model();
  m.basis.resize(9, 0);
  m.variance.resize(0);
  PcaFit fit;
  const std::vector<int> slots = {0};
  const std::vector<Vec3> local = {Vec3(50, 50, 50)};
  ASSERT_TRUE(fit.fit(m, slots, local));
  EXPECT_TRUE(fit.reconstruct(m, 2).isApprox(m.mean.segment<3>(6)));
  EXPECT_DOUBLE_EQ(fit.predictive_variance(m, 2), m.residual_variance);
}

}  // namespace
}  // namespace skinstream
