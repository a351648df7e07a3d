#pragma once
// Vertex weights inside folds (the armpit, the groin), smoothed over the detailed mesh. Beyond
// the paper.
//
// The fold blend (vertex_part_weights.h) weighs a vertex in a fold by the two marker-surface
// triangles nearest to it on either side, in straight-line distance. At the armpit those are the
// triangles of mean shift's small leftover parts, which bridge the fold, while the skin there
// moves mostly with the upper arm and the trunk, whose markers are a little farther away across
// the mesh. So here the weights of the fold's vertices (and of a band around them) are
// re-solved as a harmonic function over the detailed mesh: each is the mean of its mesh
// neighbours' weights, held by the weights of the vertices around the fold, which keep theirs.
// The weights then carry across the fold along the skin rather than through the air. A band
// around the fold's vertices (band_mm along the mesh's edges; the builder makes it half the
// median marker spacing, the scale the joints' ramp has too) is smoothed with them, each of its
// vertices also holding its own weights as strongly as one more neighbour (band_pull). A band
// in mm, not in mesh rings, keeps the region the same on a finer mesh. Vertices under a marker
// are never changed.
//
// Measured against the fold blend alone (README, "Skin deformation"): on the 25 synthetic takes
// the maximum vertex error fell in 20 (median -10 mm; the 15 maxima above 25 mm, all at the
// armpit, from 47-66 mm to 34-44 mm) and rose in none, the mean fell in 24 and p95 in 17 (rose
// in 8, by up to 0.40 mm); on 15 takes of three held-out seeds the maximum fell in 10 and rose
// in none, the mean fell in 13, and p95 fell in 9 and rose in 6.

#include <array>
#include <span>

#include "core/capture.h"

#include "core/offline/vertex_part_weights.h"

namespace skinstream {

struct FoldSmoothingOptions {
  double band_mm = 0.0;      // the band around the fold's vertices smoothed with them (0: none)
  double band_pull = 1.0;    // how strongly a band vertex holds its own weights, in mesh neighbours
  double min_weight = 0.02;  // smoothed weights at or below this are dropped, the rest renormalised
};

// vertices, faces: the detailed mesh (mm); under_marker: empty, or #V flags of the vertices that
// keep their weights (vertices_under_markers); weights: from vertex_part_weights with the fold
// blend (its in_fold flags say where the folds are), changed in place; part_count: the parts
// the weights index. Returns how many vertices were smoothed. Deterministic. Throws
// std::invalid_argument for sizes or indices that do not fit, or options out of range.
int smooth_fold_weights(std::span<const Vec3> vertices, std::span<const std::array<int, 3>> faces,
                        std::span<const char> under_marker, int part_count, VertexPartWeights& weights,
                        const FoldSmoothingOptions& options = {});

}  // namespace skinstream
