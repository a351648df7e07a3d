#pragma once
// Section 5.2, last step: the vertex weights beta_{j,p}. Each detailed vertex (registered,
// reference pose) is projected onto its nearest marker-surface triangle (reference pose; a
// bounding volume hierarchy finds it), the barycentric coordinates of the projection (clamped
// to the triangle) interpolate the three markers' alpha vectors, zeros are dropped and the
// result normalised.
//
// One addition to the paper, at hinge joints (part_joints.h): a marker speaks for its own side's
// part only up to the joint's plane (or up to its own height, when it lies past the plane); for
// a vertex further on, what the marker gives that part goes to the part of the vertex's side.
// The paper corrected the same region (upper arms and shoulders) by hand; with the nearest
// triangle alone, the inner elbow and the back of the knee, where no marker sits, follow the
// markers of the bone across the joint. Vertices under a marker (the corners of the mesh
// triangle it sits on) keep its evidence whole: the marker says best how its own skin moves.
// The switch is a linear ramp joint_blend_mm either side of the plane (or of the marker's
// height): at the plane a vertex follows both parts by half, the bisector a hinge's crease
// follows. The builder sets the width to half the median distance from a marker to its nearest
// neighbour (median_nearest_marker_distance, marker_distance_stats.h): no marker sits in the crease, so the markers place the plane no finer than their
// spacing, and a hard switch there put the inner elbow's skin wholly on one bone.
//
// A second addition, in folds (blend_folds): a vertex between its nearest triangle and a
// triangle of another part across from it (the directions to the two more than 90 degrees
// apart, the far one less than 3 times as far) takes that triangle's weights too, by inverse
// distance and fading to nothing at those limits. The nearest triangle alone flips from one part
// to the other at the middle of the fold (the armpit, the groin), where markers are 20-30 mm
// away and both sides nearly as far; the blend makes the weights continuous there. Vertices
// under a marker keep the nearest triangle alone.

#include <array>
#include <span>
#include <vector>

#include "core/capture.h"
#include "core/deform/deformation_model.h"
#include "core/deform/vertex_blend.h"
#include "core/offline/part_joints.h"

namespace skinstream {

struct VertexPartWeights {
  std::vector<int> vertex_influence_offsets{0};  // CSR over vertices, as in DeformationModel
  std::vector<PartInfluence> vertex_influences;  // beta_{j,p} > 0, sorted by part, sum 1 per vertex
  // #V: 1 where the fold blend changed the vertex's weights (a second triangle's share, which the
  // joints' split did not make the same as the nearest triangle's)
  std::vector<char> in_fold;
};

// vertices: #V detailed-mesh vertex positions in the reference pose (mm); markers: #M marker
// reference positions (mm); triangles: #T x 3 marker indices (the marker surface, at least one);
// part_member_offsets / part_members: alpha as CSR over parts (marker_part_weights.h), where
// every marker of a triangle must be a member of some part. Throws std::invalid_argument for an
// index out of range, a non-finite position, a negative weight or a triangle whose three markers
// have no weight at all. joints: empty for the paper's rule alone; their parts must be in range.
// under_marker: empty, or #V flags of the vertices that keep their markers' weights at joints
// and in folds. blend_folds: false for the nearest triangle alone. joint_blend_mm: the ramp's
// half-width at joints, 0 for a hard switch; negative or not finite is refused.
VertexPartWeights vertex_part_weights(std::span<const Vec3> vertices, std::span<const Vec3> markers,
                                      std::span<const std::array<int, 3>> triangles,
                                      std::span<const int> part_member_offsets, std::span<const PartMember> part_members,
                                      std::span<const PartJoint> joints = {}, std::span<const char> under_marker = {},
                                      bool blend_folds = false, double joint_blend_mm = 0.0);

// #V flags: the three vertices of the mesh triangle nearest to each marker (where it sits).
// Throws std::invalid_argument for a face index out of range or no faces.
std::vector<char> vertices_under_markers(std::span<const Vec3> vertices, std::span<const std::array<int, 3>> faces,
                                         std::span<const Vec3> markers);

}  // namespace skinstream
