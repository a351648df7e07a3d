#include "core/deform/part_deformation.h"

#include <algorithm>
#include <utility>

#include "core/deform/rbf_kernel.h"

namespace skinstream {

PartDeformer::PartDeformer(PartModel model, DeformationMode mode)
    : model_(std::move(model)),
      mode_(mode),
      to_local_(model_.reference_frame),
      quadratic_(identity_quadratic_transform()),
      local_now_(model_.local_reference),
      centres_(model_.local_reference),
      centres_by_row_(model_.local_reference.transpose()),
      residuals_(Eigen::MatrixX3d::Zero(model_.member_count(), 3)),
      weights_(Eigen::MatrixX3d::Zero(model_.member_count(), 3)),
      kernel_(Eigen::MatrixXd::Zero(model_.member_count(), model_.member_count())),
      kernel_lu_(model_.member_count()) {}

bool PartDeformer::uses_quadratic() const {
  return model_.quadratic && (mode_ == DeformationMode::Quadratic || mode_ == DeformationMode::QuadraticRbf);
}

bool PartDeformer::uses_rbf() const {
  return (mode_ == DeformationMode::RigidRbf || mode_ == DeformationMode::QuadraticRbf) &&
         model_.rbf_dilation > 0.0;
}

bool PartDeformer::check_members(std::span<const Vec3> member_positions_now) const {
  if (static_cast<int>(member_positions_now.size()) != model_.member_count()) return false;
  for (const Vec3& p : member_positions_now)
    if (!is_present(p)) return false;
  return true;
}

bool PartDeformer::solve(std::span<const Vec3> member_positions_now) {
  if (!check_members(member_positions_now)) return false;
  // R_t, d_t: current members as close as possible to their local part reference positions.
  fit_rigid(member_positions_now, model_.local_reference_points, to_local_);
  fit_local_deformation(member_positions_now);
  return true;
}

bool PartDeformer::solve(std::span<const Vec3> member_positions_now, const RigidTransform& segment_motion) {
  if (!check_members(member_positions_now)) return false;
  // World now -> world reference (the segment's motion undone) -> local part reference frame.
  const Eigen::Matrix3d back = segment_motion.rotation.transpose();
  to_local_.rotation = model_.reference_frame.rotation * back;
  to_local_.translation = model_.reference_frame.translation - to_local_.rotation * segment_motion.translation;
  fit_local_deformation(member_positions_now);
  return true;
}

void PartDeformer::fit_local_deformation(std::span<const Vec3> member_positions_now) {
  const int count = model_.member_count();
  for (int i = 0; i < count; ++i) local_now_.col(i) = to_local_.apply(member_positions_now[i]);

  if (uses_quadratic()) {
    // Eq. 6 written as a correction of the identity (see PartModel::reference_projection).
    quadratic_ = identity_quadratic_transform() - model_.reference_projection;
    quadratic_.noalias() += local_now_.lazyProduct(model_.pseudo_inverse);
    centres_.noalias() = quadratic_.lazyProduct(model_.quadratic_reference);
  } else {
    quadratic_ = identity_quadratic_transform();
    centres_ = model_.local_reference;
  }

  rbf_applied_ = false;
  weights_.setZero();
  if (uses_rbf()) solve_residual();
}

// Eq. 7's kernel with `ridge` on its diagonal, factored, and weights = kernel^-1 residuals.
// Cholesky first, in place in the kernel's storage: the kernel is symmetric and, with its
// ridge, usually positive definite, and LLT takes half the work of LU (the factorisation is
// most of fitting the benchmark's 148-member trunk part). The cubic B-spline kernel can be
// indefinite too (see solve_residual); LLT then reports a non-positive pivot, the kernel is
// filled again and LU with partial pivoting solves it, and that part is solved by LU from then
// on, so it never pays for both. Either way one right-hand column at a time, in place: Eigen's
// solve() with a 3-column right-hand side takes a blocking workspace from the heap on every
// call once a part has more than about 100 members (175 kB for the 148-marker trunk).
void PartDeformer::factor_and_solve(double ridge) {
  fill_rbf_kernel(centres_by_row_, model_.rbf_dilation, kernel_);
  kernel_.diagonal().array() += ridge;
  if (!kernel_indefinite_) {
    const Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>> cholesky(kernel_);
    if (cholesky.info() == Eigen::Success) {
      weights_ = residuals_;
      for (int c = 0; c < 3; ++c) {
        cholesky.matrixL().solveInPlace(weights_.col(c));
        cholesky.matrixU().solveInPlace(weights_.col(c));
      }
      return;
    }
    kernel_indefinite_ = true;
    fill_rbf_kernel(centres_by_row_, model_.rbf_dilation, kernel_);
    kernel_.diagonal().array() += ridge;
  }
  kernel_lu_.compute(kernel_);
  weights_ = kernel_lu_.permutationP() * residuals_;
  const Eigen::MatrixXd& lu = kernel_lu_.matrixLU();
  for (int c = 0; c < 3; ++c) {
    lu.triangularView<Eigen::UnitLower>().solveInPlace(weights_.col(c));
    lu.triangularView<Eigen::Upper>().solveInPlace(weights_.col(c));
  }
}

// Eq. 7: weights w with sum_i w_i phi(|p~_i - p~_j| / sigma) = r_j. The centres move every
// frame, so the kernel is rebuilt and refactored in the preallocated storage.
void PartDeformer::solve_residual() {
  residuals_ = (local_now_ - centres_).transpose();
  centres_by_row_ = centres_.transpose();
  double added = model_.rbf_ridge;  // chosen offline, the same every frame
  factor_and_solve(added);
  // The cubic B-spline is not positive definite as a radial function in 3D: with many members
  // and a wide dilation the kernel matrix can be nearly singular, and the exact weights then
  // reach thousands of times the residual and swing the surface between the members by metres.
  // A frame the part's own ridge does not tame (a pose far from the training take) gets a
  // larger one, the smallest of a few that does.
  const double limit = kMaxWeightGain * std::max(residuals_.cwiseAbs().maxCoeff(), 1e-6);
  for (double ridge : {1e-3, 1e-2, 1e-1, 1.0}) {
    if (weights_.allFinite() && weights_.cwiseAbs().maxCoeff() <= limit) break;
    if (ridge <= added) continue;
    added = ridge;
    factor_and_solve(added);
  }
  ridge_ = added;
  // Coincident centres make the kernel singular; then skip the residual rather than emit NaN.
  rbf_applied_ = weights_.allFinite();
  if (!rbf_applied_) weights_.setZero();
}

Vec3 PartDeformer::deform(const Vec3& reference_local_position) const {
  const Vec3 inside = model_.clamp_to_bounds(reference_local_position);
  Vec3 local = quadratic_ * quadratic_basis(inside);
  if (rbf_applied_) {
    const double inverse_sigma = 1.0 / model_.rbf_dilation;
    Vec3 offset = Vec3::Zero();
    for (int i = 0; i < model_.member_count(); ++i) {
      const double value = cubic_bspline_kernel((local - centres_.col(i)).norm() * inverse_sigma);
      if (value != 0.0) offset += value * weights_.row(i).transpose();
    }
    local += offset;
  }
  local += reference_local_position - inside;  // beyond the members' box: carried rigidly
  return to_local_.apply_inverse(local);
}

}  // namespace skinstream
