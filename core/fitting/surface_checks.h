#pragma once
// Is a fitted, registered or deformed body plausible? Compares it with the same mesh at rest (same
// vertices, same triangles) and measures what a crumpled or shard-sprayed body shows and an
// ordinary pose does not:
//   strain      each edge's length ratio to the reference, after removing one global scale (the
//               median ratio): r = (len / reference len) / scale, strain = max(r, 1/r);
//   flips       a triangle whose normal turned by more than 90 degrees against the reference's,
//               measured in the frame of its neighbourhood (the rotation that best maps the
//               reference positions of the vertices of the triangles around it to their new
//               ones), so that a raised arm or a rigid motion of the whole mesh turns no triangle
//               over, while a fold does (a few at the creases of a skinned pose, hundreds in a
//               crumpled or noisy mesh);
//   crossings   pairs of triangles that share no vertex and pass through each other, neither of
//               which crossed anything in the reference or touches one that did (a template can
//               come with crossings of its own, at the fingers and toes, and a small move there
//               trades one pair for its neighbour's).
// Units do not matter (every figure is a ratio or a count).
#include <span>
#include <string>
#include <vector>

#include "core/capture.h"
#include "core/geometry/triangle_mesh.h"

namespace skinstream {

// The defaults accept a body posed by linear blend skinning (its creases fold a few triangles
// and press the back of a bent knee into the thigh: the template with both knees bent 90 degrees
// crosses 0.36% of its triangles and flips 4); at_rest() is for a mesh in the reference's own
// pose (a registration of the template at rest), where nothing may fold or cross.
struct SurfaceCheckLimits {
  double max_strain = 1.5;              // an edge is strained beyond this ratio either way
  double max_strained_fraction = 0.01;  // of the edges, at most
  // No stretched edge may grow longer than this many typical edges (the reference's median edge,
  // the scale removed): a few vertices pulled far away (shards) strain too few edges for the
  // fraction to see them. Measured against a typical edge, not the edge's own rest length: the
  // tiny edges of a crease stretch many times under skinning (the armpit of a raised arm: 19
  // times, 10.4 typical edges, CMU 85_02) and stay short of a shard (hundreds); and stretch
  // only, as skinning collapses edges in creases.
  double max_edge_stretch = 25.0;
  double max_flipped_fraction = 0.001;            // of the triangles
  double max_self_intersecting_fraction = 0.005;  // of the triangles

  static SurfaceCheckLimits at_rest() {
    SurfaceCheckLimits limits;
    limits.max_flipped_fraction = 0.0;
    limits.max_self_intersecting_fraction = 0.0;
    return limits;
  }
};

struct SurfaceCheck {
  double scale = 1.0;              // global scale removed: median edge length ratio
  double strained_fraction = 0.0;  // of the edges, strain > limits.max_strain
  double max_strain = 1.0;         // the largest edge strain, either way
  double max_stretch = 1.0;        // the largest r (1 when no edge grew)
  double longest_stretched_edge = 0.0;  // of the edges that grew, the longest, in typical edges
  int strained_edges = 0;
  int edges = 0;                              // distinct edges measured (reference length > 0)
  int flipped_triangles = 0;                  // includes triangles collapsed to no area
  int self_intersecting_triangles = 0;        // triangles in a crossing pair the reference does not have
  int self_intersecting_pairs = 0;            // those pairs
  int reference_self_intersecting_pairs = 0;  // crossing pairs of the reference itself
  std::string problem;                        // empty within the limits, else one line: what and how much

  bool ok() const { return problem.empty(); }
};

// reference, vertices: #V positions (any unit, the same for both); triangles: #F x 3 vertex
// indices into both, counter-clockwise seen from outside. A vertex that is not finite makes
// `problem` say so (the other figures are then not measured). Throws std::invalid_argument
// (one line) when the sizes differ, a triangle index is out of range, a reference vertex is not
// finite, a strain limit is not above 1 or a fraction is negative.
SurfaceCheck check_surface(std::span<const Vec3> reference, std::span<const Vec3> vertices,
                           std::span<const Triangle> triangles, const SurfaceCheckLimits& limits = {});

}  // namespace skinstream
