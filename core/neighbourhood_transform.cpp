#include "core/neighbourhood_transform.h"

#include <array>

namespace skinstream {

bool neighbourhood_transform(const SubjectModel& model, int marker, std::span<const Vec3> positions,
                             std::span<const char> usable, RigidTransform& out) {
  std::array<Vec3, SubjectModel::kMaxRing> source, target;
  size_t count = 0;
  for (int k = model.ring_offsets[marker]; k < model.ring_offsets[marker + 1]; ++k) {
    const int j = model.ring[k];
    if (!is_present(positions[j]) || (!usable.empty() && !usable[j])) continue;
    source[count] = model.ring_local_reference[k];
    target[count] = positions[j];
    ++count;
  }
  if (count < 3) return false;
  fit_rigid({source.data(), count}, {target.data(), count}, out);
  return true;
}

}  // namespace skinstream
