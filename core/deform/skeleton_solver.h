#pragma once
// Per frame: the pose of a SegmentSkeleton that brings its markers' blended positions closest to
// the markers measured now (damped Gauss-Newton on each segment's rotation about its pivot and
// the root's translation, robust to a few wrong markers). Warm-started from the last frame, so
// a few steps suffice at 120 Hz. Buffers are sized at construction; solve() allocates nothing.
//
// The pose is kept as each segment's rotation relative to its parent (L_s, reference-pose axes)
// and the root's translation t. A segment's world motion maps a reference-pose point x to
//   W_s(x) = P_s + R_s (x - pivot_s),  R_s = R_parent L_s,  P_s = W_parent(pivot_s),
// the root's P = pivot + t; a marker's prediction is sum_s w_s W_s(reference position).

#include <Eigen/Core>
#include <span>
#include <vector>

#include "core/absolute_orientation.h"
#include "core/capture.h"
#include "core/deform/segment_skeleton.h"

namespace skinstream {

struct SkeletonSolverOptions {
  int max_iterations = 8;  // Gauss-Newton steps per solve at most
  // Levenberg damping (mm^2 per rad^2 of a step): a rotation no marker pins down (a twist seen
  // by no marker) stays where it was instead of wandering, while 1 rad at 300 mm from a joint
  // costs 9e4 mm^2 of residual, so observed joints are not held back.
  double damping = 1e3;
  // Huber threshold (mm): a marker that misses by more pulls with a constant force, so one
  // mislabelled marker cannot bend a limb toward it.
  double robust_mm = 30.0;
  double converged_rad = 1e-5;  // stop when no rotation step is larger than this
  // A pull of every joint but the root toward its reference (or prior_pose) rotation, in mm^2 per
  // rad^2 of the rotation away from it. 0 for the runtime (the markers say where each joint is);
  // the offline fit, which starts far from the actor's pose, uses it so that what the markers
  // do not see (a twist, a neck) stays anatomical instead of winding up.
  double prior = 0.0;
  // With twist_axes (one unit axis per segment, reference-pose axes, zero for none), the pull on
  // the rotation about that axis is twist_prior instead: a limb's twist is what its markers see
  // least, and it alone can wind up.
  std::vector<Vec3> twist_axes;
  double twist_prior = 0.0;
};

class SkeletonSolver {
 public:
  // reference_markers: the markers' reference-pose positions (mm), one per skeleton marker.
  // Throws std::invalid_argument when the skeleton does not validate or the counts differ.
  SkeletonSolver(const SegmentSkeleton& skeleton, std::span<const Vec3> reference_markers,
                 const SkeletonSolverOptions& options = {});

  // Fits the pose to `markers` (skeleton order, mm); non-finite markers are left out. Starts
  // from the current pose. Returns the number of steps taken.
  int solve(std::span<const Vec3> markers);
  void reset();  // back to the reference pose

  int segment_count() const { return static_cast<int>(parent_.size()); }
  int marker_count() const { return static_cast<int>(reference_.size()); }
  // Reference pose -> now (world, mm), of the current pose.
  const RigidTransform& segment_motion(int segment) const { return motion_[static_cast<size_t>(segment)]; }
  Vec3 predicted_marker(int marker) const;
  double rms_mm() const { return rms_mm_; }  // over the markers used by the last solve
  int markers_used() const { return used_; }

  // The pose itself, for the offline fit (which carries it across changes of the skeleton).
  const std::vector<Eigen::Matrix3d>& local_rotations() const { return local_; }
  const Vec3& root_translation() const { return translation_; }
  void set_pose(std::span<const Eigen::Matrix3d> local_rotations, const Vec3& root_translation);
  // The rotations options.prior pulls toward (default: the reference pose, every one identity).
  void set_prior_pose(std::span<const Eigen::Matrix3d> local_rotations);

 private:
  void update_motions();
  // Adds one marker's rows to the normal equations (or only its residual when rows is false).
  void accumulate(int marker, const Vec3& measured, bool rows);

  SkeletonSolverOptions options_;
  std::vector<int> parent_;
  std::vector<Vec3> pivot_;
  std::vector<int> weight_offsets_;
  std::vector<SegmentWeight> weights_;
  std::vector<Vec3> reference_;

  std::vector<Eigen::Matrix3d> local_;
  std::vector<Eigen::Matrix3d> prior_;
  Vec3 translation_ = Vec3::Zero();
  std::vector<RigidTransform> motion_;  // x -> R_s x + (P_s - R_s pivot_s)
  std::vector<Vec3> world_pivot_;       // P_s

  // Scratch, sized once.
  Eigen::MatrixXd normal_;   // J^T W J + damping
  Eigen::VectorXd gradient_; // J^T W e
  Eigen::VectorXd step_;
  std::vector<double> chain_weight_;  // per segment: a marker's weight on it and its descendants
  std::vector<Vec3> chain_point_;     // per segment: the same weights times the moved point
  std::vector<int> touched_;          // the segments a marker's chains reach
  std::vector<Eigen::Matrix3d> block_;  // per touched segment: d marker / d rotation step
  double rms_mm_ = 0.0;
  double squared_sum_ = 0.0;
  int used_ = 0;
};

}  // namespace skinstream
