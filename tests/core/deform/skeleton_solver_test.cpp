#include "core/deform/skeleton_solver.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>

#include "support/allocation_counter.h"

namespace skinstream {
namespace {

// A small body: a root (pelvis) with a spine, and from the spine an upper arm, a forearm and a
// hand; from the root a thigh and a shank. Markers sit around each segment, some shared
// between two segments near the joints.
struct Rig {
  SegmentSkeleton skeleton;
  std::vector<Vec3> reference;
};

Rig make_rig(uint32_t seed) {
  Rig rig;
  auto add = [&](const char* name, int parent, Vec3 pivot) {
    rig.skeleton.segments.push_back({name, parent, pivot});
    return rig.skeleton.segment_count() - 1;
  };
  const int root = add("pelvis", -1, {0, 0, 1000});
  const int spine = add("spine", root, {0, 0, 1100});
  const int upper = add("upperarm", spine, {200, 0, 1450});
  const int fore = add("forearm", upper, {450, 0, 1450});
  const int hand = add("hand", fore, {700, 0, 1450});
  const int thigh = add("thigh", root, {100, 0, 950});
  const int shank = add("shank", thigh, {100, 0, 520});
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> around(-60.0, 60.0);
  auto marker = [&](Vec3 at, std::vector<SegmentWeight> weights) {
    rig.reference.push_back(at + Vec3(around(random), around(random), around(random)));
    for (const SegmentWeight& w : weights) rig.skeleton.marker_weights.push_back(w);
    rig.skeleton.marker_weight_offsets.push_back(static_cast<int>(rig.skeleton.marker_weights.size()));
  };
  for (int k = 0; k < 4; ++k) marker({0, 0, 1000}, {{root, 1.0}});
  for (int k = 0; k < 4; ++k) marker({0, 0, 1300}, {{spine, 1.0}});
  for (int k = 0; k < 2; ++k) marker({320, 0, 1450}, {{upper, 1.0}});
  marker({450, 0, 1450}, {{upper, 0.5}, {fore, 0.5}});
  for (int k = 0; k < 2; ++k) marker({580, 0, 1450}, {{fore, 1.0}});
  marker({700, 0, 1450}, {{fore, 0.3}, {hand, 0.7}});
  for (int k = 0; k < 2; ++k) marker({780, 0, 1450}, {{hand, 1.0}});
  for (int k = 0; k < 2; ++k) marker({100, 0, 750}, {{thigh, 1.0}});
  marker({100, 0, 520}, {{thigh, 0.6}, {shank, 0.4}});
  for (int k = 0; k < 2; ++k) marker({100, 0, 300}, {{shank, 1.0}});
  rig.skeleton.part_segment = {root, spine, upper, fore, hand, thigh, shank};
  return rig;
}

std::vector<Eigen::Matrix3d> random_pose(int segments, std::mt19937& random, double degrees) {
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<Eigen::Matrix3d> pose;
  for (int s = 0; s < segments; ++s) {
    const Vec3 axis = Vec3(normal(random), normal(random), normal(random)).normalized();
    pose.push_back(Eigen::AngleAxisd(degrees * M_PI / 180.0 * std::abs(normal(random)) / 1.5, axis).toRotationMatrix());
  }
  return pose;
}

std::vector<Vec3> markers_of(const Rig& rig, std::span<const Eigen::Matrix3d> pose, const Vec3& translation) {
  SkeletonSolver truth(rig.skeleton, rig.reference);
  truth.set_pose(pose, translation);
  std::vector<Vec3> out;
  for (int i = 0; i < truth.marker_count(); ++i) out.push_back(truth.predicted_marker(i));
  return out;
}

TEST(SkeletonSolver, RefusesASkeletonThatDoesNotMatchItsMarkers) {
  Rig rig = make_rig(1);
  rig.reference.pop_back();
  EXPECT_THROW(SkeletonSolver(rig.skeleton, rig.reference), std::invalid_argument);
  rig = make_rig(1);
  rig.skeleton.marker_weights[0].weight = 0.5;  // the first marker's weights no longer sum to 1
  EXPECT_THROW(SkeletonSolver(rig.skeleton, rig.reference), std::invalid_argument);
  rig = make_rig(1);
  rig.skeleton.segments[2].parent = 3;  // after itself
  EXPECT_THROW(SkeletonSolver(rig.skeleton, rig.reference), std::invalid_argument);
}

TEST(SkeletonSolver, AtTheReferencePoseEverySegmentStaysPut) {
  const Rig rig = make_rig(2);
  SkeletonSolver solver(rig.skeleton, rig.reference);
  solver.solve(rig.reference);
  EXPECT_LT(solver.rms_mm(), 1e-9);
  for (int s = 0; s < solver.segment_count(); ++s) {
    EXPECT_TRUE(solver.segment_motion(s).rotation.isIdentity(1e-12));
    EXPECT_LT(solver.segment_motion(s).translation.norm(), 1e-9);
  }
}

TEST(SkeletonSolver, RecoversAPoseFromTheReferencePose) {
  for (uint32_t seed = 1; seed <= 20; ++seed) {
    const Rig rig = make_rig(seed);
    std::mt19937 random(seed);
    const std::vector<Eigen::Matrix3d> pose = random_pose(rig.skeleton.segment_count(), random, 40.0);
    const Vec3 translation(150.0, -80.0, 30.0);
    const std::vector<Vec3> measured = markers_of(rig, pose, translation);
    SkeletonSolverOptions options;
    options.max_iterations = 100;
    options.damping = 10.0;  // exact data: the damping only slows the weakly seen rotations down
    SkeletonSolver solver(rig.skeleton, rig.reference, options);
    solver.solve(measured);
    EXPECT_LT(solver.rms_mm(), 0.01) << "seed " << seed;
    // Every marker's segment is where the truth put it (the markers pin every rotation down).
    SkeletonSolver truth(rig.skeleton, rig.reference);
    truth.set_pose(pose, translation);
    for (int s = 0; s < solver.segment_count(); ++s)
      EXPECT_LT((solver.segment_motion(s).rotation - truth.segment_motion(s).rotation).norm(), 1e-3)
          << "seed " << seed << " segment " << s;
  }
}

TEST(SkeletonSolver, OneWrongMarkerBendsNothingFar) {
  const Rig rig = make_rig(3);
  std::mt19937 random(3);
  const std::vector<Eigen::Matrix3d> pose = random_pose(rig.skeleton.segment_count(), random, 30.0);
  std::vector<Vec3> measured = markers_of(rig, pose, Vec3::Zero());
  const std::vector<Vec3> truth = measured;
  measured[12] += Vec3(0.0, 400.0, 0.0);  // a forearm marker swapped with something 40 cm away
  auto worst_other = [&](double robust_mm) {
    SkeletonSolverOptions options;
    options.max_iterations = 50;
    options.robust_mm = robust_mm;
    SkeletonSolver solver(rig.skeleton, rig.reference, options);
    solver.solve(measured);
    double worst = 0.0;
    for (int i = 0; i < solver.marker_count(); ++i)
      if (i != 12) worst = std::max(worst, (solver.predicted_marker(i) - truth[i]).norm());
    return worst;
  };
  // Least squares bends the forearm toward the wrong marker; the robust weight bounds its pull.
  const double plain = worst_other(1e9), robust = worst_other(30.0);
  EXPECT_GT(plain, 40.0);
  EXPECT_LT(robust, plain / 2.0);
}

TEST(SkeletonSolver, LeavesMissingMarkersOut) {
  const Rig rig = make_rig(4);
  std::mt19937 random(4);
  const std::vector<Eigen::Matrix3d> pose = random_pose(rig.skeleton.segment_count(), random, 30.0);
  std::vector<Vec3> measured = markers_of(rig, pose, Vec3::Zero());
  const Vec3 hidden = measured[5];
  measured[5] = missing_point();  // a spine marker: three others still hold the spine
  SkeletonSolverOptions options;
  options.max_iterations = 50;
  SkeletonSolver solver(rig.skeleton, rig.reference, options);
  solver.solve(measured);
  EXPECT_EQ(solver.markers_used(), solver.marker_count() - 1);
  EXPECT_LT((solver.predicted_marker(5) - hidden).norm(), 0.05);
}

TEST(SkeletonSolver, TracksAMotionFrameByFrameWithoutAllocating) {
  const Rig rig = make_rig(5);
  std::mt19937 random(5);
  const std::vector<Eigen::Matrix3d> start = random_pose(rig.skeleton.segment_count(), random, 20.0);
  const std::vector<Eigen::Matrix3d> end = random_pose(rig.skeleton.segment_count(), random, 20.0);
  SkeletonSolver solver(rig.skeleton, rig.reference);
  for (int frame = 0; frame <= 120; ++frame) {
    const double t = frame / 120.0;
    std::vector<Eigen::Matrix3d> pose;
    for (size_t s = 0; s < start.size(); ++s)
      pose.push_back(Eigen::Quaterniond(start[s]).slerp(t, Eigen::Quaterniond(end[s])).toRotationMatrix());
    const std::vector<Vec3> measured = markers_of(rig, pose, Vec3(t * 500.0, 0.0, 0.0));
    size_t allocations = 0;
    {
      test::CountAllocations counter;
      solver.solve(measured);
      allocations = counter.count();
    }
    EXPECT_EQ(allocations, 0u) << "frame " << frame;
    if (frame > 0) {
      EXPECT_LT(solver.rms_mm(), 0.05) << "frame " << frame;
    }
  }
}

}  // namespace
}  // namespace skinstream
