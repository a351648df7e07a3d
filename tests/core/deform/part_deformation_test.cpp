#include "core/deform/part_deformation.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include "core/deform/rbf_kernel.h"
#include "tests/core/deform/deform_test_support.h"
#include "tests/support/allocation_counter.h"

namespace skinstream {
namespace {

using deform_test::deform_non_rigidly;
using deform_test::move_rigidly;
using deform_test::random_motion;
using deform_test::random_points;

double max_member_error(const PartDeformer& part, const std::vector<Vec3>& now) {
  double worst = 0.0;
  for (int i = 0; i < part.model().member_count(); ++i)
    worst = std::max(worst, (part.deform(part.model().local_reference_points[i]) - now[i]).norm());
  return worst;
}

// Octant-symmetric members (+-a, +-b, +-c) for three generators: Q0 has rank 9, and a field of
// diagonal stretch plus mixed terms keeps the centroid and a symmetric positive cross-covariance,
// so Horn returns the applied motion exactly and A must come back exactly.
std::vector<Vec3> octant_symmetric_members() {
  std::vector<Vec3> points;
  for (const Vec3& g : {Vec3(100, 50, 20), Vec3(60, 70, 35), Vec3(30, 20, 45)})
    for (int sx : {-1, 1})
      for (int sy : {-1, 1})
        for (int sz : {-1, 1}) points.push_back(Vec3(sx * g.x(), sy * g.y(), sz * g.z()) + Vec3(500, 40, 1000));
  return points;
}

TEST(PartDeformer, SolveRejectsWrongCountAndMissingMembers) {
  std::mt19937_64 rng(10);
  const std::vector<Vec3> members = random_points(rng, 12, Vec3(100, 60, 40));
  PartDeformer part(build_part_model(members));
  const std::vector<Vec3> moved = move_rigidly(members, random_motion(rng));
  ASSERT_TRUE(part.solve(moved));
  const Vec3 before = part.deform(Vec3(10, 20, 30));

  EXPECT_FALSE(part.solve(std::span<const Vec3>(moved).first(11)));
  std::vector<Vec3> with_gap = members;
  with_gap[3] = missing_point();
  EXPECT_FALSE(part.solve(with_gap));
  EXPECT_EQ(part.deform(Vec3(10, 20, 30)), before);  // previous frame kept
}

TEST(PartDeformer, BeforeFirstSolveIsReferencePose) {
  std::mt19937_64 rng(11);
  const std::vector<Vec3> members = random_points(rng, 12, Vec3(100, 60, 40));
  const PartDeformer part(build_part_model(members));
  const Vec3 vertex(320, -150, 880);
  EXPECT_LT((part.deform(part.model().local_from_world(vertex)) - vertex).norm(), 1e-9);
}

TEST(PartDeformer, RigidMotionReproducedForAnyVertexInAllModes) {
  std::mt19937_64 rng(12);
  const std::vector<Vec3> members = random_points(rng, 20, Vec3(120, 60, 40));
  const std::vector<Vec3> vertices = random_points(rng, 200, Vec3(200, 120, 80));  // also outside the hull
  const RigidTransform motion = random_motion(rng);
  for (DeformationMode mode : kDeformationModes) {
    PartDeformer part(build_part_model(members), mode);
    ASSERT_TRUE(part.solve(move_rigidly(members, motion)));
    double worst = 0.0;
    for (const Vec3& v : vertices)
      worst = std::max(worst, (part.deform(part.model().local_from_world(v)) - motion.apply(v)).norm());
    EXPECT_LT(worst, 1e-6) << static_cast<int>(mode);
  }
}

// A skeleton-driven part takes its rigid transform from its segment: with the members moved by
// that same motion nothing is left for eqs. 6-7, and every point follows the motion.
TEST(PartDeformer, AGivenSegmentMotionMovesThePartExactly) {
  std::mt19937_64 rng(21);
  const std::vector<Vec3> members = random_points(rng, 5, Vec3(120, 60, 40));
  const std::vector<Vec3> vertices = random_points(rng, 100, Vec3(200, 120, 80));
  const RigidTransform motion = random_motion(rng);
  for (DeformationMode mode : kDeformationModes) {
    PartModel model = build_part_model(members);
    model.quadratic = false;  // as a part with a few members of a sparse set
    PartDeformer part(model, mode);
    ASSERT_TRUE(part.solve(move_rigidly(members, motion), motion));
    double worst = 0.0;
    for (const Vec3& v : vertices)
      worst = std::max(worst, (part.deform(part.model().local_from_world(v)) - motion.apply(v)).norm());
    EXPECT_LT(worst, 1e-6) << static_cast<int>(mode);
  }
}

// What the segment's motion leaves at the members is interpolated by eq. 7 alone when the part
// has no quadratic: the members are reached, and the quadratic transform stays the identity.
TEST(PartDeformer, AGivenMotionLeavesTheMembersToTheResidual) {
  std::mt19937_64 rng(22);
  const std::vector<Vec3> members = random_points(rng, 5, Vec3(120, 60, 40));
  const RigidTransform motion = random_motion(rng);
  std::vector<Vec3> now = move_rigidly(members, motion);
  now[2] += Vec3(4.0, -3.0, 2.0);  // the skin moved a little off the segment
  PartModel model = build_part_model(members);
  model.quadratic = false;
  PartDeformer part(model, DeformationMode::QuadraticRbf);
  ASSERT_TRUE(part.solve(now, motion));
  EXPECT_TRUE(part.quadratic_transform().isApprox(identity_quadratic_transform()));
  EXPECT_TRUE(part.rbf_applied());
  EXPECT_LT(max_member_error(part, now), 1e-6);
}

TEST(PartDeformer, QuadraticFieldRecoveredExactly) {
  const std::vector<Vec3> members = octant_symmetric_members();
  const PartModel model = build_part_model(members);
  ASSERT_EQ(model.quadratic_rank, 9);
  QuadraticTransform truth = QuadraticTransform::Zero();
  truth.leftCols<3>() = Eigen::Vector3d(1.05, 0.97, 1.1).asDiagonal();
  truth.rightCols<3>() << 2e-3, -1e-3, 5e-4, 1e-3, 3e-3, -2e-3, -5e-4, 1e-3, 2e-3;  // mixed terms
  std::mt19937_64 rng(13);
  const RigidTransform motion = random_motion(rng);
  std::vector<Vec3> now(members.size());
  for (size_t i = 0; i < members.size(); ++i)
    now[i] = motion.apply(model.reference_frame.apply_inverse(truth * model.quadratic_reference.col(i)));

  PartDeformer quadratic(model, DeformationMode::Quadratic);
  ASSERT_TRUE(quadratic.solve(now));
  EXPECT_LT((quadratic.quadratic_transform() - truth).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_LT(max_member_error(quadratic, now), 1e-9);

  // Rigid mode leaves the non-rigid part as residual: members are missed by millimetres, and
  // each lands exactly where the rigid fit puts its reference position.
  PartDeformer rigid(model, DeformationMode::Rigid);
  ASSERT_TRUE(rigid.solve(now));
  EXPECT_GT(max_member_error(rigid, now), 1.0);
  for (int i = 0; i < model.member_count(); ++i) {
    const Vec3& reference = model.local_reference_points[i];
    EXPECT_LT((rigid.deform(reference) - rigid.to_local().apply_inverse(reference)).norm(), 1e-9);
  }
}

TEST(PartDeformer, ResidualModesInterpolateMembersExactly) {
  std::mt19937_64 rng(14);
  const std::vector<Vec3> members = random_points(rng, 30, Vec3(120, 60, 40));
  const std::vector<Vec3> now = deform_non_rigidly(members, random_motion(rng));
  for (DeformationMode mode : {DeformationMode::RigidRbf, DeformationMode::QuadraticRbf}) {
    PartDeformer part(build_part_model(members), mode);
    ASSERT_TRUE(part.solve(now));
    EXPECT_TRUE(part.rbf_applied());
    EXPECT_LT(max_member_error(part, now), 1e-6) << static_cast<int>(mode);
  }
  // Without residuals, quadratic follows the markers better than rigid (Figure 7 b vs c).
  PartDeformer rigid(build_part_model(members), DeformationMode::Rigid);
  PartDeformer quadratic(build_part_model(members), DeformationMode::Quadratic);
  ASSERT_TRUE(rigid.solve(now));
  ASSERT_TRUE(quadratic.solve(now));
  EXPECT_LT(max_member_error(quadratic, now), max_member_error(rigid, now));
}

// Eq. 7 is solved by Cholesky while the kernel is positive definite and by LU once it is not
// (the cubic B-spline is not positive definite in 3D): either way the weights solve the system
// and, with no ridge, the members are interpolated. 30 random members give a positive definite
// kernel here and 60 an indefinite one, which no Cholesky factorisation exists for; both
// asserted, so each path is known to run, and neither allocates.
TEST(PartDeformer, KernelSolvedExactlyWhetherPositiveDefiniteOrNot) {
  for (int count : {30, 60}) {
    std::mt19937_64 rng(12);
    const std::vector<Vec3> members = random_points(rng, count, Vec3(120, 60, 40));
    const std::vector<Vec3> now = deform_non_rigidly(members, random_motion(rng));
    PartDeformer part(build_part_model(members), DeformationMode::QuadraticRbf);
    for (int frame = 0; frame < 2; ++frame) {  // the second solve of an indefinite part takes LU directly
      size_t allocations = 0;
      {
        test::CountAllocations counter;
        ASSERT_TRUE(part.solve(now));
        allocations = counter.count();
      }
      EXPECT_EQ(allocations, 0u) << count << " members, frame " << frame;
      ASSERT_TRUE(part.rbf_applied());
      ASSERT_EQ(part.rbf_ridge(), 0.0);
      Eigen::MatrixXd kernel(count, count);
      fill_rbf_kernel(part.rbf_centres().transpose(), part.model().rbf_dilation, kernel);
      const double lowest = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(kernel).eigenvalues().minCoeff();
      if (count == 30) {
        EXPECT_GT(lowest, 0.0);
      } else {
        EXPECT_LT(lowest, -1e-3);
      }
      const Eigen::MatrixX3d residuals = (part.local_positions() - part.rbf_centres()).transpose();
      EXPECT_LT((kernel * part.rbf_weights() - residuals).cwiseAbs().maxCoeff(), 1e-9) << count;
      EXPECT_LT(max_member_error(part, now), 1e-6) << count;
    }
  }
}

// A near-singular kernel (coplanar members under a wide dilation: the cubic B-spline is not
// positive definite in 3D) gets a ridge that keeps the weights within kMaxWeightGain times the
// largest residual, instead of weights thousands of times the residual.
TEST(PartDeformer, NearSingularKernelGetsARidgeAndBoundedWeights) {
  // Like the trunk of the synthetic body: ~150 members on a sheet, a few irregular clusters.
  std::mt19937_64 rng(15);
  const std::vector<Vec3> coplanar = random_points(rng, 150, Vec3(300, 170, 0));
  const RigidTransform motion = random_motion(rng);
  PartDeformer part(build_part_model(coplanar), DeformationMode::QuadraticRbf);
  ASSERT_TRUE(part.solve(deform_non_rigidly(coplanar, motion)));
  ASSERT_TRUE(part.rbf_applied());
  EXPECT_GT(part.rbf_ridge(), 0.0);
  const double residual = (part.local_positions() - part.rbf_centres()).cwiseAbs().maxCoeff();
  EXPECT_LE(part.rbf_weights().cwiseAbs().maxCoeff(), PartDeformer::kMaxWeightGain * residual);
}

// The model's ridge: eq. 7 with lambda on the kernel diagonal, so at each member the fit falls
// short of the marker by exactly lambda times its weight (Phi w = r - lambda w).
TEST(PartDeformer, ModelRidgeSmoothsTheResidualByExactlyItsShare) {
  std::mt19937_64 rng(16);
  const std::vector<Vec3> members = random_points(rng, 30, Vec3(120, 60, 40));
  const std::vector<Vec3> now = deform_non_rigidly(members, random_motion(rng));
  PartModel model = build_part_model(members);
  model.rbf_ridge = 0.05;
  PartDeformer part(model, DeformationMode::QuadraticRbf);
  ASSERT_TRUE(part.solve(now));
  ASSERT_TRUE(part.rbf_applied());
  EXPECT_EQ(part.rbf_ridge(), 0.05);
  double smallest_gap = 1e9;
  for (int i = 0; i < model.member_count(); ++i) {
    const Vec3 fitted = part.to_local().apply(part.deform(model.local_reference_points[i]));
    const Vec3 expected = part.local_positions().col(i) - 0.05 * part.rbf_weights().row(i).transpose();
    EXPECT_LT((fitted - expected).norm(), 1e-6) << i;
    smallest_gap = std::min(smallest_gap, (fitted - part.local_positions().col(i)).norm());
  }
  EXPECT_GT(smallest_gap, 0.0);  // no longer an interpolant
}

TEST(PartDeformer, DegenerateMemberSetsGiveNoNaN) {
  std::mt19937_64 rng(15);
  std::vector<Vec3> collinear;
  for (int i = 0; i < 5; ++i) collinear.push_back(Vec3(1, 2, 3) * (10.0 * i));
  const std::vector<std::vector<Vec3>> cases = {random_points(rng, 4, Vec3(50, 50, 50)),
                                                random_points(rng, 8, Vec3(50, 40, 30)),
                                                random_points(rng, 12, Vec3(100, 50, 0)),
                                                collinear,
                                                {Vec3(4, 5, 6)},
                                                {Vec3(1, 1, 1), Vec3(1, 1, 1), Vec3(9, 1, 1)}};
  const std::vector<Vec3> vertices = random_points(rng, 50, Vec3(150, 150, 150), Vec3::Zero());
  const RigidTransform motion = random_motion(rng);
  for (size_t k = 0; k < cases.size(); ++k) {
    for (DeformationMode mode : kDeformationModes) {
      PartDeformer part(build_part_model(cases[k]), mode);
      const std::vector<Vec3> now = deform_non_rigidly(cases[k], motion);
      ASSERT_TRUE(part.solve(now));
      for (const Vec3& v : vertices) ASSERT_TRUE(is_present(part.deform(v))) << k << " mode " << static_cast<int>(mode);
      // Non-coincident members are still interpolated by the full method: exactly while the
      // kernel is well conditioned, to a small fraction of the residual when a ridge was needed.
      if (mode == DeformationMode::QuadraticRbf && k < 4) {
        if (part.rbf_ridge() == 0.0) {
          EXPECT_LT(max_member_error(part, now), 1e-6) << k;
        } else {
          const double residual = (part.local_positions() - part.rbf_centres()).cwiseAbs().maxCoeff();
          EXPECT_LT(max_member_error(part, now), 0.1 * residual) << k;
        }
      }
    }
  }
}

TEST(PartDeformer, SolveAndDeformAllocateNothing) {
  {  // the counter must see an allocation, or a zero below proves nothing
    test::CountAllocations control;
    std::vector<double> buffer(16);
    EXPECT_GT(control.count(), 0u);
  }
  std::mt19937_64 rng(16);
  for (int count : {6, 40}) {  // 40 members exercises Eigen's blocked LU path
    const std::vector<Vec3> members = random_points(rng, count, Vec3(150, 80, 50));
    const std::vector<Vec3> now = deform_non_rigidly(members, random_motion(rng));
    PartDeformer part(build_part_model(members));
    Vec3 sum = Vec3::Zero();
    size_t allocations = 0;
    {
      test::CountAllocations counter;
      part.solve(now);
      for (const Vec3& reference : part.model().local_reference_points) sum += part.deform(reference);
      allocations = counter.count();
    }
    EXPECT_EQ(allocations, 0u) << count;
    EXPECT_TRUE(is_present(sum));
  }
}

}  // namespace
}  // namespace skinstream
