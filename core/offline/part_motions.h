#pragma once
// Each part's rigid motion over a training take: per frame, Horn's fit of the part's chosen
// markers from their reference positions to where they are in that frame. Shared by the marker
// weights (how well a part's motion explains a marker) and the joints (where two parts' motions
// agree).

#include <span>
#include <vector>

#include "core/absolute_orientation.h"
#include "core/capture.h"

namespace skinstream {

// reference: #M marker positions; fitted[p]: the markers part p is fitted to (indices checked by
// the caller; an empty list gives the identity); positions: frame_count x #M, frame-major.
// Returns part_count x frame_count transforms, part-major: [p * frame_count + f].
std::vector<RigidTransform> fit_part_motions(std::span<const Vec3> reference,
                                             const std::vector<std::vector<int>>& fitted,
                                             std::span<const Vec3> positions, int frame_count);

}  // namespace skinstream
