#pragma once
// Joints between near-rigid parts, found from the training take: two parts that turn about a
// common point (an elbow, a knee) share a functional joint centre, the point that both parts'
// rigid motions carry to the same place in every frame (least squares, as in the SCoRE method of
// Ehrig et al. 2006). Used by the vertex weights: at a fold no marker sits in (the inner elbow,
// the back of the knee), the nearest marker-surface triangle often belongs to the part on the
// other side of the joint, and the plane through the joint centre says which side a vertex is on.
//
// A pair of parts counts as jointed when it turns like a hinge about a common point:
// - the centre's residual (how far the two motions carry it apart, RMS over the take) is at most
//   max_residual_ratio of how far the two motions carry the parts' own markers apart;
// - the relative rotation keeps to one axis: of the least-squares system's normal matrix
//   sum_f (R_a - R_b)^T (R_a - R_b), which for a relative turn by theta about n is
//   2 (1 - cos theta) (I - n n^T), the smallest eigenvalue is at most max_axis_spread of the
//   largest.
// A ball joint under a mass of tissue (a shoulder with its shoulder blade, a hip) has no crease
// a plane could follow, and splitting there made the skin worse on the procedural mannequin.
// Pairs that merely slide against each other (trunk pieces) have no common point at all.

#include <array>
#include <span>
#include <vector>

#include "core/capture.h"
#include "core/deform/deformation_model.h"

namespace skinstream {

struct PartJointOptions {
  // Over five synthetic MakeHuman subjects the pairs taken (the elbows and knees, and once a
  // small part at a knee) came at 0.4-4.2% and at 0.000-0.011; of the other pairs, those under
  // 0.05 on one criterion were at 0.072 or more on the other. Two parts that move nearly
  // together may pass as well; splitting them is harmless, both sides move alike.
  double max_residual_ratio = 0.05;
  double max_axis_spread = 0.05;
};

struct PartJoint {
  int first = 0, second = 0;  // parts, first < second
  Vec3 centre = Vec3::Zero();  // reference pose (mm)
  Vec3 axis = Vec3::UnitZ();   // unit, from the first part's markers' centroid towards the second's
  double residual_mm = 0.0;         // RMS distance between the centre as carried by either part
  double relative_motion_mm = 0.0;  // RMS distance between the parts' markers as carried by either part
  double axis_spread = 0.0;         // smallest / largest eigenvalue of the normal matrix (0: a hinge)

  // Which side of the plane through the centre across the axis: > 0 the second part's.
  double side(const Vec3& p) const { return (p - centre).dot(axis); }
};

// reference: #M marker reference positions (mm); part_member_offsets / part_members: alpha as
// CSR over parts (marker_part_weights.h); training: frame_count x #M, frame-major, all present.
// A part's rigid motion per frame is fitted (Horn) to the markers it owns outright (weight 1), or
// to all its members when fewer than 3. With the marker weights' boundary a ring wider
// (marker_part_weights.h), these lie a ring deeper inside the part than the markers the marker
// weights fit its motion to: a joint needs the bone's turn, which the deeper markers give best.
// (Fitting both from the marker weights' markers, one fit instead of two, was measured over the
// 25 synthetic takes: seed 4 and the mannequin lose an elbow and a maximum rises by 16 mm; both
// from the deeper markers is worse still, mean higher in 20 of 25.) Returns the jointed pairs,
// ordered by (first, second).
// Deterministic. Throws std::invalid_argument for sizes or indices that do not fit, a non-finite
// position or a ratio that is not positive.
std::vector<PartJoint> fit_part_joints(std::span<const Vec3> reference, std::span<const int> part_member_offsets,
                                       std::span<const PartMember> part_members, std::span<const Vec3> training,
                                       int frame_count, const PartJointOptions& options = {});

}  // namespace skinstream
