#pragma once
// Offline, per-part data of section 5.3 that does not change per frame: the local part reference
// frame, the members' local part reference positions p^0 and quadratic vectors Q^0, the
// pseudo-inverse factor of eq. 6 and the RBF dilation sigma of eq. 7. Coordinates in mm.

#include <Eigen/Core>
#include <vector>

#include "core/absolute_orientation.h"
#include "core/capture.h"
#include "core/deform/quadratic_basis.h"

namespace skinstream {

struct PartModel {
  // World reference pose -> local part reference frame: origin at the members' mean, axes the
  // covariance eigenvectors (largest variance first, det +1). The paper's R^0_p, d^0_p.
  RigidTransform reference_frame;

  std::vector<Vec3> local_reference_points;       // p^0_i, for the Horn fit
  Eigen::Matrix3Xd local_reference;               // the same, 3 x Y
  Eigen::Matrix<double, 9, Eigen::Dynamic> quadratic_reference;  // Q^0, 9 x Y

  // Y x 9 factor M with A = P M (eq. 6: M = Q0^T [Q0 Q0^T]^-1 when Q0 has rank 9). Computed as a
  // truncated-SVD pseudo-inverse of Q0 in scale-normalised coordinates, so it also exists for
  // fewer than 9 members or coplanar/collinear members.
  Eigen::Matrix<double, Eigen::Dynamic, 9> pseudo_inverse;
  // P^0 M. Equals [I 0 0] when Q0 has rank 9. The runtime fit uses A = [I 0 0] + (P - P^0) M so
  // that a rank-deficient Q0 still maps the rest pose to itself (minimum-norm deviation from
  // the identity instead of a minimum-norm A, which would shrink unconstrained directions).
  QuadraticTransform reference_projection = QuadraticTransform::Zero();
  int quadratic_rank = 0;  // numerical rank of Q0 (9 = full quadratic fit)
  // Ridge on the six quadratic modes of eq. 6, per member, in the scaled coordinates of the
  // fit: 0 is the paper's least-squares fit; larger values draw the fit towards the linear
  // modes alone. With only a few members more than the 9 modes, the exact fit follows every
  // wobble of the skin with curvature between the markers (measured: 70-126 mm maxima on a held
  // out synthetic subject); the subject builder chooses it per part by leave-one-out error over
  // the training take (core/offline/quadratic_ridge_selection.h).
  double quadratic_ridge = 0.0;
  // Whether eq. 6 is fitted at all. A part driven by a skeleton with only a few members (a
  // sparse marker set) keeps its segment's rigid motion and interpolates what is left by eq. 7
  // alone: a quadratic through three or four markers bends the whole part to follow one of them.
  bool quadratic = true;

  // sigma of eq. 7: twice the largest nearest-member distance. 0 when the residual cannot be
  // interpolated (fewer than 2 distinct members); the RBF term is then skipped.
  double rbf_dilation = 0.0;
  // Added to the diagonal of eq. 7's kernel matrix (kernel units, phi(0) = 2/3): 0 interpolates
  // the members exactly, as the paper writes it; the subject builder chooses it per part by
  // leave-one-out error over the training take (core/offline/rbf_ridge_selection.h).
  double rbf_ridge = 0.0;

  // The members' bounding box in the local part frame. The quadratic field (and the RBF
  // residual) are evaluated at the nearest point of this box and the rest of the offset is
  // carried rigidly: a quadratic fitted to the members is an interpolant inside their hull but
  // grows without bound outside it (hands, head and feet, which carry no markers, would fly off).
  Vec3 local_min = Vec3::Zero();
  Vec3 local_max = Vec3::Zero();
  Vec3 clamp_to_bounds(const Vec3& local) const { return local.cwiseMax(local_min).cwiseMin(local_max); }

  int member_count() const { return static_cast<int>(local_reference_points.size()); }
  // World reference position -> local part reference position (where deform() takes its input).
  Vec3 local_from_world(const Vec3& world_reference_position) const {
    return reference_frame.apply(world_reference_position);
  }
};

// Throws std::invalid_argument for no members, a non-finite position or a negative or
// non-finite ridge.
PartModel build_part_model(const std::vector<Vec3>& reference_member_positions, double quadratic_ridge = 0.0);

}  // namespace skinstream
