#include "core/deform/part_model.h"

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <limits>
#include <stdexcept>

#include "tests/core/deform/deform_test_support.h"

namespace skinstream {
namespace {

using deform_test::random_points;

TEST(PartModel, RejectsEmptyAndNonFiniteMembers) {
  EXPECT_THROW(build_part_model({}), std::invalid_argument);
  EXPECT_THROW(build_part_model({Vec3(1, 2, 3), missing_point()}), std::invalid_argument);
  EXPECT_THROW(build_part_model({Vec3(1, std::numeric_limits<double>::infinity(), 3)}), std::invalid_argument);
}

TEST(PartModel, FrameIsCentredProperRotationAlongPrincipalAxes) {
  std::mt19937_64 rng(1);
  const std::vector<Vec3> members = random_points(rng, 30, Vec3(120, 60, 25));
  const PartModel model = build_part_model(members);
  const Eigen::Matrix3d& r = model.reference_frame.rotation;
  EXPECT_NEAR(r.determinant(), 1.0, 1e-12);
  EXPECT_TRUE((r * r.transpose()).isApprox(Eigen::Matrix3d::Identity(), 1e-12));
  EXPECT_LT(model.local_reference.rowwise().mean().norm(), 1e-9);
  const Eigen::Matrix3d covariance = model.local_reference * model.local_reference.transpose() / 30.0;
  EXPECT_LT((covariance - Eigen::Matrix3d(covariance.diagonal().asDiagonal())).cwiseAbs().maxCoeff(), 1e-8);
  EXPECT_GT(covariance(0, 0), covariance(1, 1));
  EXPECT_GT(covariance(1, 1), covariance(2, 2));
  EXPECT_TRUE(model.local_from_world(members[4]).isApprox(model.local_reference_points[4], 1e-12));
}

TEST(PartModel, PseudoInverseMatchesEquation6WhenFullRank) {
  std::mt19937_64 rng(2);
  const PartModel model = build_part_model(random_points(rng, 25, Vec3(100, 80, 60)));
  ASSERT_EQ(model.quadratic_rank, 9);
  const Eigen::MatrixXd& q0 = model.quadratic_reference;
  const Eigen::MatrixXd paper = q0.transpose() * (q0 * q0.transpose()).inverse();
  EXPECT_LT((model.pseudo_inverse - paper).cwiseAbs().maxCoeff() / paper.cwiseAbs().maxCoeff(), 1e-8);
  EXPECT_LT((model.reference_projection - identity_quadratic_transform()).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(QuadraticTransform, RecoveredExactlyFromQuadraticField) {
  // Eq. 6 alone: P^t = A Q^0 with >= 9 members in general position gives back A.
  std::mt19937_64 rng(3);
  const PartModel model = build_part_model(random_points(rng, 15, Vec3(100, 80, 60)));
  ASSERT_EQ(model.quadratic_rank, 9);
  QuadraticTransform truth = identity_quadratic_transform();
  std::normal_distribution<double> g;
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) truth(r, c) += 0.05 * g(rng);
  for (int c = 3; c < 9; ++c)
    for (int r = 0; r < 3; ++r) truth(r, c) = 1e-3 * g(rng);  // ~10 mm at 100 mm
  const Eigen::Matrix3Xd local_now = truth * model.quadratic_reference;
  const QuadraticTransform recovered = local_now * model.pseudo_inverse;
  EXPECT_LT((recovered - truth).leftCols<3>().cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_LT((recovered - truth).rightCols<6>().cwiseAbs().maxCoeff(), 1e-11);  // per mm^2
}

TEST(PartModel, DilationIsTwiceLargestNearestMemberDistance) {
  const PartModel model = build_part_model({Vec3(0, 0, 0), Vec3(10, 0, 0), Vec3(30, 0, 0)});
  EXPECT_NEAR(model.rbf_dilation, 40.0, 1e-12);
}

TEST(PartModel, DegenerateMemberSetsStayFinite) {
  std::mt19937_64 rng(4);
  std::vector<Vec3> coplanar = random_points(rng, 12, Vec3(100, 50, 0));
  std::vector<Vec3> collinear;
  for (int i = 0; i < 5; ++i) collinear.push_back(Vec3(1, 2, 3) * (10.0 * i));
  const std::vector<std::vector<Vec3>> cases = {
      random_points(rng, 4, Vec3(50, 50, 50)), coplanar, collinear, {Vec3(4, 5, 6)}, {Vec3(1, 1, 1), Vec3(1, 1, 1)}};
  // Fewer than 9 members: the linear modes only (rank <= 3); 12 coplanar members: the 5 modes
  // the plane determines.
  const std::vector<int> expected_rank = {3, 5, 1, 0, 0};
  for (size_t k = 0; k < cases.size(); ++k) {
    const PartModel model = build_part_model(cases[k]);
    EXPECT_TRUE(model.pseudo_inverse.allFinite()) << k;
    EXPECT_TRUE(model.reference_projection.allFinite()) << k;
    EXPECT_TRUE(model.reference_frame.rotation.allFinite()) << k;
    EXPECT_EQ(model.quadratic_rank, expected_rank[k]) << k;
  }
  EXPECT_EQ(build_part_model({Vec3(4, 5, 6)}).rbf_dilation, 0.0);
  EXPECT_EQ(build_part_model({Vec3(1, 1, 1), Vec3(1, 1, 1)}).rbf_dilation, 0.0);
}

// The ridge on the quadratic modes: 0 is eq. 6 as before; any ridge keeps the rest pose; a
// large one leaves the linear fit alone; a bad one is refused.
TEST(PartModel, QuadraticRidgeShrinksOnlyTheQuadraticModes) {
  std::mt19937_64 rng(5);
  const std::vector<Vec3> members = random_points(rng, 20, Vec3(100, 80, 60));
  const PartModel exact = build_part_model(members);
  EXPECT_EQ(build_part_model(members, 0.0).pseudo_inverse, exact.pseudo_inverse);
  EXPECT_THROW(build_part_model(members, -1.0), std::invalid_argument);
  EXPECT_THROW(build_part_model(members, std::numeric_limits<double>::quiet_NaN()), std::invalid_argument);
  EXPECT_THROW(build_part_model(members, std::numeric_limits<double>::infinity()), std::invalid_argument);

  // A field with both linear and quadratic parts, as eq. 6 fits it from the members.
  QuadraticTransform truth = identity_quadratic_transform();
  std::normal_distribution<double> g;
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) truth(r, c) += 0.05 * g(rng);
  for (int c = 3; c < 9; ++c)
    for (int r = 0; r < 3; ++r) truth(r, c) = 1e-3 * g(rng);
  const Eigen::Matrix3Xd now = truth * exact.quadratic_reference;
  double previous_curvature = std::numeric_limits<double>::infinity();
  for (double ridge : {1e-3, 1e-1, 10.0, 1e4}) {
    const PartModel model = build_part_model(members, ridge);
    EXPECT_DOUBLE_EQ(model.quadratic_ridge, ridge);
    EXPECT_LT((model.reference_projection * model.quadratic_reference - model.local_reference).cwiseAbs().maxCoeff(), 1e-9)
        << "the rest pose moves at ridge " << ridge;
    const QuadraticTransform fitted =
        identity_quadratic_transform() - model.reference_projection + now * model.pseudo_inverse;
    const double curvature = fitted.rightCols<6>().norm();
    EXPECT_LT(curvature, previous_curvature) << ridge;
    previous_curvature = curvature;
  }
  // At the top of the range the quadratic modes are gone: the linear fit alone (what parts of
  // fewer than 9 members get).
  Eigen::MatrixXd linear = exact.quadratic_reference.topRows(3);
  const Eigen::Matrix3d linear_only = now * linear.transpose() * (linear * linear.transpose()).inverse();
  const QuadraticTransform top =
      identity_quadratic_transform() - build_part_model(members, 1e4).reference_projection +
      now * build_part_model(members, 1e4).pseudo_inverse;
  EXPECT_LT(top.rightCols<6>().cwiseAbs().maxCoeff(), 1e-3 * truth.rightCols<6>().cwiseAbs().maxCoeff());
  EXPECT_LT((top.leftCols<3>() - linear_only).cwiseAbs().maxCoeff(), 1e-3);
}

}  // namespace
}  // namespace skinstream
