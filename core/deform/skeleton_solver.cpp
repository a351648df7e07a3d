#include "core/deform/skeleton_solver.h"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace skinstream {

namespace {

Eigen::Matrix3d skew(const Vec3& v) {
  Eigen::Matrix3d m;
  m << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return m;
}

}  // namespace

SkeletonSolver::SkeletonSolver(const SegmentSkeleton& skeleton, std::span<const Vec3> reference_markers,
                               const SkeletonSolverOptions& options)
    : options_(options) {
  const std::string problem = skeleton.validate(static_cast<int>(reference_markers.size()),
                                                static_cast<int>(skeleton.part_segment.size()));
  if (!problem.empty()) throw std::invalid_argument(problem);
  for (const Vec3& p : reference_markers)
    if (!p.allFinite()) throw std::invalid_argument("skeleton solver: a reference marker is not finite");
  const int segments = skeleton.segment_count();
  for (const SkeletonSegment& s : skeleton.segments) {
    parent_.push_back(s.parent);
    pivot_.push_back(s.pivot);
  }
  weight_offsets_ = skeleton.marker_weight_offsets;
  weights_ = skeleton.marker_weights;
  reference_.assign(reference_markers.begin(), reference_markers.end());
  local_.assign(static_cast<size_t>(segments), Eigen::Matrix3d::Identity());
  prior_ = local_;
  motion_.resize(static_cast<size_t>(segments));
  world_pivot_.resize(static_cast<size_t>(segments));
  const int unknowns = 3 * segments + 3;
  normal_ = Eigen::MatrixXd::Zero(unknowns, unknowns);
  gradient_ = Eigen::VectorXd::Zero(unknowns);
  step_ = Eigen::VectorXd::Zero(unknowns);
  chain_weight_.assign(static_cast<size_t>(segments), 0.0);
  chain_point_.assign(static_cast<size_t>(segments), Vec3::Zero());
  touched_.reserve(static_cast<size_t>(segments));
  block_.resize(static_cast<size_t>(segments));
  update_motions();
}

void SkeletonSolver::reset() {
  std::fill(local_.begin(), local_.end(), Eigen::Matrix3d::Identity());
  translation_.setZero();
  update_motions();
}

void SkeletonSolver::set_pose(std::span<const Eigen::Matrix3d> local_rotations, const Vec3& root_translation) {
  if (static_cast<int>(local_rotations.size()) != segment_count())
    throw std::invalid_argument("skeleton solver: a pose of " + std::to_string(local_rotations.size()) +
                                " rotations for " + std::to_string(segment_count()) + " segments");
  std::copy(local_rotations.begin(), local_rotations.end(), local_.begin());
  translation_ = root_translation;
  update_motions();
}

void SkeletonSolver::set_prior_pose(std::span<const Eigen::Matrix3d> local_rotations) {
  if (static_cast<int>(local_rotations.size()) != segment_count())
    throw std::invalid_argument("skeleton solver: a prior pose of " + std::to_string(local_rotations.size()) +
                                " rotations for " + std::to_string(segment_count()) + " segments");
  std::copy(local_rotations.begin(), local_rotations.end(), prior_.begin());
}

void SkeletonSolver::update_motions() {
  for (int s = 0; s < segment_count(); ++s) {
    const int p = parent_[s];
    Eigen::Matrix3d rotation;
    if (p < 0) {
      rotation = local_[s];
      world_pivot_[s] = pivot_[s] + translation_;
    } else {
      rotation = motion_[p].rotation * local_[s];
      world_pivot_[s] = motion_[p].apply(pivot_[s]);
    }
    motion_[s].rotation = rotation;
    motion_[s].translation = world_pivot_[s] - rotation * pivot_[s];
  }
}

Vec3 SkeletonSolver::predicted_marker(int marker) const {
  Vec3 sum = Vec3::Zero();
  for (int k = weight_offsets_[marker]; k < weight_offsets_[marker + 1]; ++k)
    sum += weights_[k].weight * motion_[weights_[k].segment].apply(reference_[marker]);
  return sum;
}

// The marker's prediction m = sum_q w_q W_q(r). A rotation step a_s of segment s (in its
// parent's axes) turns every descendant q about P_s by R_parent a_s, so
//   dm / da_s = -[y_s - c_s P_s]x R_parent,  c_s = sum of w_q over the q below s, y_s = sum w_q W_q(r),
// and dm / dt = I for the root's translation.
void SkeletonSolver::accumulate(int marker, const Vec3& measured, bool rows) {
  touched_.clear();
  Vec3 predicted = Vec3::Zero();
  for (int k = weight_offsets_[marker]; k < weight_offsets_[marker + 1]; ++k) {
    const SegmentWeight& w = weights_[k];
    const Vec3 moved = w.weight * motion_[w.segment].apply(reference_[marker]);
    predicted += moved;
    if (!rows) continue;
    for (int s = w.segment; s >= 0; s = parent_[s]) {
      if (chain_weight_[s] == 0.0) touched_.push_back(s);
      chain_weight_[s] += w.weight;
      chain_point_[s] += moved;
    }
  }
  const Vec3 residual = predicted - measured;
  const double miss = residual.norm();
  squared_sum_ += miss * miss;
  ++used_;
  if (!rows) return;
  const double robust = miss > options_.robust_mm ? options_.robust_mm / miss : 1.0;
  const int root_column = 3 * segment_count();
  for (size_t a = 0; a < touched_.size(); ++a) {
    const int s = touched_[a];
    const Eigen::Matrix3d turn = parent_[s] < 0 ? Eigen::Matrix3d::Identity() : motion_[parent_[s]].rotation;
    block_[a] = -skew(chain_point_[s] - chain_weight_[s] * world_pivot_[s]) * turn;
    chain_weight_[s] = 0.0;
    chain_point_[s].setZero();
  }
  for (size_t a = 0; a < touched_.size(); ++a) {
    const int ca = 3 * touched_[a];
    gradient_.segment<3>(ca).noalias() += robust * block_[a].transpose() * residual;
    for (size_t b = 0; b < touched_.size(); ++b)
      normal_.block<3, 3>(ca, 3 * touched_[b]).noalias() += robust * block_[a].transpose() * block_[b];
    normal_.block<3, 3>(ca, root_column).noalias() += robust * block_[a].transpose();
    normal_.block<3, 3>(root_column, ca).noalias() += robust * block_[a];
  }
  gradient_.segment<3>(root_column) += robust * residual;
  normal_.block<3, 3>(root_column, root_column).diagonal().array() += robust;
}

int SkeletonSolver::solve(std::span<const Vec3> markers) {
  if (static_cast<int>(markers.size()) != marker_count())
    throw std::invalid_argument("skeleton solver: " + std::to_string(markers.size()) + " markers for " +
                                std::to_string(marker_count()));
  const int root_column = 3 * segment_count();
  int steps = 0;
  for (; steps < options_.max_iterations; ++steps) {
    normal_.setZero();
    gradient_.setZero();
    squared_sum_ = 0.0;
    used_ = 0;
    for (int i = 0; i < marker_count(); ++i)
      if (is_present(markers[i])) accumulate(i, markers[i], true);
    if (used_ == 0) break;
    normal_.diagonal().head(root_column).array() += options_.damping;
    if (options_.prior > 0.0 || options_.twist_prior > 0.0) {
      // The rotation from the prior to the current one, phi = log(L P^T), in the parent's axes,
      // where a step a moves it by about a (first order; enough to hold unseen joints).
      for (int s = 1; s < segment_count(); ++s) {
        const Eigen::AngleAxisd away(local_[s] * prior_[s].transpose());
        Eigen::Matrix3d weight = options_.prior * Eigen::Matrix3d::Identity();
        if (static_cast<int>(options_.twist_axes.size()) == segment_count()) {
          const Vec3& a = options_.twist_axes[s];
          weight += (options_.twist_prior - options_.prior) * a * a.transpose();
        }
        gradient_.segment<3>(3 * s) += weight * (away.angle() * away.axis());
        normal_.block<3, 3>(3 * s, 3 * s) += weight;
      }
    }
    normal_.diagonal().tail<3>().array() += 1e-6;  // the root's translation is always seen
    Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>> cholesky(normal_);
    if (cholesky.info() != Eigen::Success) break;
    step_ = -gradient_;
    cholesky.matrixL().solveInPlace(step_);
    cholesky.matrixU().solveInPlace(step_);
    double largest = 0.0;
    for (int s = 0; s < segment_count(); ++s) {
      const Vec3 a = step_.segment<3>(3 * s);
      const double angle = a.norm();
      largest = std::max(largest, angle);
      if (angle > 0.0) {
        local_[s] = Eigen::AngleAxisd(angle, a / angle).toRotationMatrix() * local_[s];
        // Keep it a rotation: one Gram-Schmidt pass is enough for steps this small.
        Eigen::Matrix3d& r = local_[s];
        r.col(0).normalize();
        r.col(1) -= r.col(0).dot(r.col(1)) * r.col(0);
        r.col(1).normalize();
        r.col(2) = r.col(0).cross(r.col(1));
      }
    }
    translation_ += step_.tail<3>();
    update_motions();
    if (largest < options_.converged_rad) {
      ++steps;
      break;
    }
  }
  squared_sum_ = 0.0;
  used_ = 0;
  for (int i = 0; i < marker_count(); ++i)
    if (is_present(markers[i])) accumulate(i, markers[i], false);
  rms_mm_ = used_ > 0 ? std::sqrt(squared_sum_ / used_) : 0.0;
  return steps;
}

}  // namespace skinstream
