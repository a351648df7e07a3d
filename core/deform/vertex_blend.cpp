#include "core/deform/vertex_blend.h"

#include <cmath>

namespace skinstream {

bool normalize_influences(std::span<PartInfluence> influences) {
  double sum = 0.0;
  for (const PartInfluence& influence : influences) {
    if (!(influence.weight >= 0.0)) return false;  // also rejects NaN
    sum += influence.weight;
  }
  if (!(sum > 0.0) || !std::isfinite(sum)) return false;
  for (PartInfluence& influence : influences) influence.weight /= sum;
  return true;
}

Vec3 blend_vertex(const Vec3& world_reference_position, std::span<const PartInfluence> influences,
                  std::span<const PartDeformer> parts) {
  Vec3 blended = Vec3::Zero();
  for (const PartInfluence& influence : influences) {
    if (influence.part < 0 || influence.part >= static_cast<int>(parts.size())) return missing_point();
    const PartDeformer& part = parts[influence.part];
    blended += influence.weight * part.deform(part.model().local_from_world(world_reference_position));
  }
  return blended;
}

}  // namespace skinstream
