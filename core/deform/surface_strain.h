#pragma once
// How far a mesh has moved from its rest shape, in the two ways a crumpled or sprayed body
// shows and an ordinary pose does not (the runtime half of core/fitting/surface_checks.h, so
// that the daemon can check a subject's body when it loads it):
//   strain  each edge's length ratio to the reference after removing one global scale (the
//           median ratio): r = (len / reference len) / scale, strain = max(r, 1/r); and the
//           longest stretched edge against a typical edge (the reference's median, scaled), a
//           shard's mark: the tiny edges of a crease stretch many times under skinning and stay
//           short;
//   flips   a triangle whose normal turned by more than 90 degrees against the reference's, in
//           the frame of its neighbourhood (the rotation that best maps the reference positions
//           of the vertices around it to their new ones): a bent knee is no flip.
// Units do not matter. Inputs must be finite and the same size (the callers check).

#include <span>

#include "core/capture.h"

namespace skinstream {

struct EdgeStrain {
  double scale = 1.0;                   // median edge length ratio
  double strained_fraction = 0.0;       // of the edges, strain > max_strain
  double max_strain = 1.0;
  double max_stretch = 1.0;             // the largest r (1 when no edge grew)
  double longest_stretched_edge = 0.0;  // of the edges that grew, the longest, in typical edges
  int strained_edges = 0;
  int edges = 0;                        // edges measured (reference length > 0)
};

EdgeStrain measure_edge_strain(std::span<const Vec3> reference, std::span<const Vec3> vertices,
                               std::span<const std::array<int, 3>> triangles, double max_strain);

// Triangles turned over against their neighbourhood (and triangles collapsed to no area).
int count_flipped_triangles(std::span<const Vec3> reference, std::span<const Vec3> vertices,
                            std::span<const std::array<int, 3>> triangles);

}  // namespace skinstream
