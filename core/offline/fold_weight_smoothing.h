#pragma once
// Vertex weights inside folds (the armpit, the groin), smoothed over the detailed mesh. Beyond
// the paper.
//
// The fold blend (vertex_part_weights.h) weighs a vertex in a fold by the two marker-surface
// triangles nearest to it on either side, in straight-line distance. At the armpit those are the
// triangles of mean shift's small leftover parts, which bridge the fold, while the skin there
// moves mostly with the upper arm and the trunk, whose markers are a little farther away across
// the mesh. So here the weights of the fold's vertices (and of one mesh ring around them) are
// re-solved as a harmonic function over the detailed mesh: each is the mean of its mesh
// neighbours' weights, held by the weights of the vertices around the fold, which keep theirs.
// The weights then carry across the fold along the skin rather than through the air. A vertex
// of the ring around the fold also holds its own weights, as strongly as one more neighbour
// (ring_pull). Vertices under a marker are never changed.
//
// Measured against the fold blend alone (README, "Skin deformation"): on the 25 synthetic takes
// the maximum vertex error fell in 20 (median -10 mm; the armpit's 47-66 mm maxima to 33-45 mm)
// and rose in none, the mean fell in 22 and p95 in 16 (rose in 9, by up to 0.38 mm); on 15
// takes of three held-out seeds the maximum fell in 10 and rose in none, the mean fell in 10,
// and p95 fell in 7 and rose in 8 (by up to 0.38 mm).

#include <array>
#include <span>

#include "core/offline/vertex_part_weights.h"

namespace skinstream {

struct FoldSmoothingOptions {
  int rings = 1;             // mesh rings around the fold's vertices smoothed with them
  double ring_pull = 1.0;    // how strongly a ring vertex holds its own weights, in mesh neighbours
  double min_weight = 0.02;  // smoothed weights at or below this are dropped, the rest renormalised
};

// faces: the detailed mesh's triangles (vertex indices); under_marker: empty, or #V flags of the
// vertices that keep their weights (vertices_under_markers); weights: from vertex_part_weights
// with the fold blend (its in_fold flags say where the folds are), changed in place. part_count:
// the parts the weights index. Returns how many vertices were smoothed. Deterministic. Throws
// std::invalid_argument for sizes or indices that do not fit, or options out of range.
int smooth_fold_weights(std::span<const std::array<int, 3>> faces, std::span<const char> under_marker, int part_count,
                        VertexPartWeights& weights, const FoldSmoothingOptions& options = {});

}  // namespace skinstream
