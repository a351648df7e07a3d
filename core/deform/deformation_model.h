#pragma once
// The per-subject data of section 5, built offline once (skinstream build-subject --mesh) and
// read-only at runtime: the detailed mesh registered to the marker surface in the reference
// pose (5.1), the near-rigid parts with their member markers and weights alpha (5.2), and the
// per-vertex part weights beta (5.2, barycentric from the nearest marker-surface triangle).

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/capture.h"
#include "core/deform/segment_skeleton.h"
#include "core/deform/vertex_blend.h"

namespace skinstream {

// A marker's membership of a part: alpha_{i,p} > 0.
struct PartMember {
  int marker = 0;
  double weight = 0.0;
};

struct DeformationModel {
  std::vector<Vec3> reference_vertices;        // v_j^0, registered, mm
  std::vector<std::array<int, 3>> faces;       // counter-clockwise seen from outside

  std::vector<std::string> part_names;
  std::vector<int> part_member_offsets{0};     // CSR over parts
  std::vector<PartMember> part_members;
  // Per part the ridge of eq. 7 (PartModel::rbf_ridge), chosen by leave-one-out error over the
  // training take; empty (a subject file before version 3): 0 for every part.
  std::vector<double> part_rbf_ridge;
  // Per part the ridge on eq. 6's quadratic modes (PartModel::quadratic_ridge), chosen by
  // leave-one-out error over the training take; empty (a subject file before version 4): 0.
  std::vector<double> part_quadratic_ridge;

  std::vector<int> vertex_influence_offsets{0};  // CSR over vertices
  std::vector<PartInfluence> vertex_influences;  // beta_{j,p}, each vertex sums to 1

  double registration_rms_mm = 0.0;  // marker-to-surface distance after registration

  // A body fitted to a sparse marker set (core/fitting): each part's rigid transform is its
  // segment's motion in this skeleton's pose, fitted to all markers each frame, instead of the
  // Horn fit of its own members. Empty: the paper's parts (a subject file before version 6, or
  // a dense set).
  SegmentSkeleton skeleton;
  // Per part, whether eq. 6 is fitted (PartModel::quadratic); empty: every part.
  std::vector<uint8_t> part_quadratic;
  // The fitted template in its rest pose before registration, same topology: what the checks
  // compare the registered mesh's edges with. Empty when the mesh was not fitted.
  std::vector<Vec3> rest_vertices;

  int vertex_count() const { return static_cast<int>(reference_vertices.size()); }
  int face_count() const { return static_cast<int>(faces.size()); }
  int part_count() const { return static_cast<int>(part_names.size()); }
  // Part with the largest beta (for colouring a segmentation view).
  int dominant_part(int vertex) const;

  // Empty when consistent with a subject of `marker_count` markers; otherwise what is wrong.
  std::string validate(int marker_count) const;
};

}  // namespace skinstream
