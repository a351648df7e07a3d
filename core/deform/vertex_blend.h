#pragma once
// Eq. 9: a vertex's deformed position is the weighted sum of the positions each influencing
// part gives it (eq. 8), v_j = sum_p beta_{j,p} v_{j,p}.

#include <span>

#include "core/capture.h"
#include "core/deform/part_deformation.h"

namespace skinstream {

struct PartInfluence {
  int part = 0;        // index into the deformer list
  double weight = 0.0;  // beta_{j,p}
};

// Scales the weights to sum to 1. Returns false, leaving them unchanged, when the sum is not a
// positive finite number or a weight is negative.
bool normalize_influences(std::span<PartInfluence> influences);

// Eq. 9 with the weights as given (normalise them first). The vertex is given in the world
// reference pose; each part maps it into its own local reference frame. Returns a missing point
// for an out-of-range part index.
Vec3 blend_vertex(const Vec3& world_reference_position, std::span<const PartInfluence> influences,
                  std::span<const PartDeformer> parts);

}  // namespace skinstream
