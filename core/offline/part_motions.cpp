#include "core/offline/part_motions.h"

namespace skinstream {

std::vector<RigidTransform> fit_part_motions(std::span<const Vec3> reference,
                                             const std::vector<std::vector<int>>& fitted,
                                             std::span<const Vec3> positions, int frame_count) {
  const size_t m = reference.size();
  std::vector<RigidTransform> motion(fitted.size() * static_cast<size_t>(frame_count));
  std::vector<Vec3> source, target;
  for (size_t p = 0; p < fitted.size(); ++p) {
    if (fitted[p].empty()) continue;
    source.clear();
    for (int i : fitted[p]) source.push_back(reference[i]);
    target.resize(source.size());
    for (int f = 0; f < frame_count; ++f) {
      for (size_t k = 0; k < source.size(); ++k) target[k] = positions[static_cast<size_t>(f) * m + fitted[p][k]];
      fit_rigid(source, target, motion[p * frame_count + f]);
    }
  }
  return motion;
}

}  // namespace skinstream
