#pragma once
// Per-frame deformation of one rigid part (section 5.3, eqs. 6-8): rigid transform by Horn,
// quadratic transformation by the precomputed pseudo-inverse, RBF interpolation of the residual.
// All buffers are sized at construction; solve() and deform() allocate nothing.

#include <Eigen/Core>
#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <span>

#include "core/absolute_orientation.h"
#include "core/capture.h"
#include "core/deform/part_model.h"
#include "core/deform/quadratic_basis.h"

namespace skinstream {

// The paper's comparison variants (Figure 7 b-e).
enum class DeformationMode { Rigid, Quadratic, RigidRbf, QuadraticRbf };
inline constexpr DeformationMode kDeformationModes[] = {DeformationMode::Rigid, DeformationMode::Quadratic,
                                                    DeformationMode::RigidRbf, DeformationMode::QuadraticRbf};

class PartDeformer {
 public:
  explicit PartDeformer(PartModel model, DeformationMode mode = DeformationMode::QuadraticRbf);

  // Fits the part to the members' current world positions (same order as the model's members).
  // Returns false, leaving the previous state, when the count differs or a position is missing.
  // Before the first successful solve the part is in its reference pose.
  bool solve(std::span<const Vec3> member_positions_now);
  // The same with the rigid transform given instead of Horn's: the motion of the part's
  // skeleton segment from the reference pose to now (world). The members (there may be none)
  // then only feed eqs. 6-7.
  bool solve(std::span<const Vec3> member_positions_now, const RigidTransform& segment_motion);

  // Eq. 8: local part reference position -> deformed world position at the solved frame. Outside
  // the members' bounding box the field is that of the nearest box point plus the rigid offset
  // (PartModel::clamp_to_bounds); inside, eq. 8 as written.
  Vec3 deform(const Vec3& reference_local_position) const;

  const PartModel& model() const { return model_; }
  DeformationMode mode() const { return mode_; }
  const RigidTransform& to_local() const { return to_local_; }          // world -> local: R_t, d_t
  const QuadraticTransform& quadratic_transform() const { return quadratic_; }  // A_t
  const Eigen::Matrix3Xd& local_positions() const { return local_now_; }        // p^t
  const Eigen::Matrix3Xd& rbf_centres() const { return centres_; }               // p~ = A_t q^0
  const Eigen::MatrixX3d& rbf_weights() const { return weights_; }               // w_i, Y x 3
  // False when this frame's kernel matrix was singular; the residual is then not applied.
  bool rbf_applied() const { return rbf_applied_; }
  // The ridge added to this frame's kernel diagonal (0: exact interpolation at the members): the
  // model's rbf_ridge, or more on a frame whose weights it does not keep in bounds.
  double rbf_ridge() const { return ridge_; }
  // Weights beyond this multiple of the largest residual mean a near-singular kernel.
  static constexpr double kMaxWeightGain = 200.0;

 private:
  bool uses_quadratic() const;
  bool uses_rbf() const;
  bool check_members(std::span<const Vec3> member_positions_now) const;
  void fit_local_deformation(std::span<const Vec3> member_positions_now);
  void solve_residual();
  void factor_and_solve(double ridge);

  PartModel model_;
  DeformationMode mode_;
  RigidTransform to_local_;
  QuadraticTransform quadratic_;
  Eigen::Matrix3Xd local_now_;
  Eigen::Matrix3Xd centres_;
  Eigen::MatrixX3d centres_by_row_;  // the same, one per row, as fill_rbf_kernel reads them
  Eigen::MatrixX3d residuals_;
  Eigen::MatrixX3d weights_;
  Eigen::MatrixXd kernel_;  // eq. 7's kernel, or its Cholesky factor once factored in place
  Eigen::PartialPivLU<Eigen::MatrixXd> kernel_lu_;
  bool kernel_indefinite_ = false;  // LLT failed once: solved by LU from then on
  bool rbf_applied_ = false;
  double ridge_ = 0.0;
};

}  // namespace skinstream
