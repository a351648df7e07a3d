#pragma once
// Section 5.2, second half: the marker weights alpha_{i,p}. A marker whose marker-surface
// triangles all lie in one part is inside it (weight 1). A boundary marker is compared with the
// rigid motion of each neighbouring part (the parts of its triangles), fitted per frame by Horn
// from the part's inside markers: its RMS error e_p over the take gives a Gaussian likelihood
// exp(-e_p^2 / (2 sigma_p^2)) (after Anguelov et al. 2004), normalised over the neighbouring
// parts; parts under the threshold (0.2 in the paper) are dropped and the rest renormalised.
// sigma_p is the RMS over the take of the part's inside markers' own errors under that motion
// (how far a marker that truly belongs strays), floored at sigma_floor_mm so that a perfectly
// rigid part does not turn every small error into a zero likelihood.
//
// One addition to the paper (boundary_rings): the boundary is widened by whole rings of the
// marker surface. A marker within that many edges of another part's triangle is weighed by
// likelihood too, among the parts of the triangles around it; the parts' motions are still
// fitted from the inside markers in the paper's sense. With the paper's one-triangle boundary,
// the skin a marker spacing (~45 mm) in from a seam follows its part alone, while the skin
// there moves partly with the part across; and the markers of mean shift's small leftover
// parts at the shoulders, nearly all a ring from a seam, follow those poorly rigid parts alone.

#include <array>
#include <span>
#include <vector>

#include "core/capture.h"
#include "core/deform/deformation_model.h"

namespace skinstream {

struct MarkerWeightOptions {
  double threshold = 0.2;       // drop a part whose normalised likelihood is not above this
  double sigma_floor_mm = 1.0;  // lower bound of a part's sigma
  int min_members = 4;          // every part keeps at least this many markers
  int boundary_rings = 1;       // 0: the paper's boundary, a marker with triangles in several parts
};

struct MarkerPartWeights {
  std::vector<int> part_member_offsets{0};  // CSR over parts, as in DeformationModel
  std::vector<PartMember> part_members;     // sorted by marker within a part; weights in (0, 1]
  std::vector<double> part_sigma_mm;        // #parts: sigma_p used
  std::vector<int> inside_markers;          // #parts: how many markers are inside each part
  int boundary_markers = 0;                 // markers weighed by likelihood (within boundary_rings of a seam)
  int markers_added_for_min_members = 0;    // memberships added so parts keep min_members

  // alpha_{i,p} of one marker, 0 when it is not a member (a linear scan; for tests and tools).
  double weight(int marker, int part) const;
};

// reference: #M marker positions of the reference pose (mm); triangles: #T x 3 marker indices;
// triangle_part: #T part indices in [0, part_count) (see part_segmentation.h), every part with a
// triangle; positions: frame_count x #M, frame-major, all present.
//
// Parts with fewer than 3 inside markers are fitted from all their triangles' markers instead.
// A marker in no triangle is treated as a boundary marker of every part. When a part ends with
// fewer than min_members markers, the markers of its triangles it dropped are added back (best
// likelihood first, then nearest in the reference pose among all markers), with their
// normalised likelihood for it, and each such marker's weights renormalised: so a marker added
// this way may lose weight 1 elsewhere (counted in markers_added_for_min_members).
// Every marker's weights sum to 1. Deterministic. Throws std::invalid_argument for sizes or
// indices that do not fit, a part without triangles, a non-finite position or bad options.
MarkerPartWeights marker_part_weights(std::span<const Vec3> reference, std::span<const std::array<int, 3>> triangles,
                                      std::span<const int> triangle_part, int part_count, std::span<const Vec3> positions,
                                      int frame_count, const MarkerWeightOptions& options = {});

}  // namespace skinstream
