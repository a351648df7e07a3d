#include "core/synth/body_region.h"

#include <algorithm>
#include <cmath>

namespace skinstream::synth {

double Region::weight(const Vec3& p, const Vec3& n, double mask) const {
  double w = mask_bones.empty() ? 1.0 : std::clamp(mask, 0.0, 1.0);
  if (w <= 0.0) return 0.0;
  const Vec3 d = p - centre;
  const double along = d.dot(axis);
  if (std::isfinite(sigma_along)) w *= std::exp(-0.5 * (along / sigma_along) * (along / sigma_along));
  if (std::isfinite(sigma_across)) {
    const double across2 = (d - along * axis).squaredNorm();
    w *= std::exp(-0.5 * across2 / (sigma_across * sigma_across));
  }
  if (facing.squaredNorm() > 0.0) {
    const double c = n.dot(facing);
    w *= c > 0.0 ? std::pow(c, facing_power) : 0.0;
  }
  return w;
}

Footprint footprint(const Region& region, const std::vector<Vec3>& rest,
                    const std::vector<Vec3>& rest_normals, const SkinWeights& weights, double min_weight) {
  Footprint f;
  for (int v = 0; v < static_cast<int>(rest.size()); ++v) {
    double mask = 0.0;
    for (int b : region.mask_bones) mask += weights.weight(v, b);
    const double w = region.weight(rest[static_cast<size_t>(v)], rest_normals[static_cast<size_t>(v)], mask);
    if (w >= min_weight) {
      f.vertices.push_back(v);
      f.weights.push_back(w);
    }
  }
  return f;
}

}  // namespace skinstream::synth
