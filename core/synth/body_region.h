#pragma once
// A soft patch of the rest-pose body surface where a deformer acts: a smooth weight in [0, 1]
// per vertex from a Gaussian around a centre (separately along an axis and across it), a
// facing lobe on the rest normal and a mask from the skin weights of chosen bones. Because it
// is defined in rest space, the same region gives matching weights on the body and on its
// subdivided version.
#include <limits>
#include <vector>

#include "core/body/body.h"

namespace skinstream::synth {

struct Region {
  Vec3 centre = Vec3::Zero();                                     // rest, mm
  Vec3 axis = Vec3::UnitZ();                                      // unit
  double sigma_along = std::numeric_limits<double>::infinity();   // mm along the axis from the centre
  double sigma_across = std::numeric_limits<double>::infinity();  // mm from the axis line
  Vec3 facing = Vec3::Zero();                                     // unit; zero = no facing lobe
  double facing_power = 1.0;                                      // weight *= max(0, n . facing)^power
  std::vector<int> mask_bones;  // weight *= sum of skin weights on these bones; empty = no mask

  // Weight of a point with rest normal n whose skin weights on mask_bones sum to `mask`.
  double weight(const Vec3& p, const Vec3& n, double mask) const;
};

// Vertices with non-negligible weight, in increasing order.
struct Footprint {
  std::vector<int> vertices;
  std::vector<double> weights;
};

Footprint footprint(const Region& region, const std::vector<Vec3>& rest,
                    const std::vector<Vec3>& rest_normals, const SkinWeights& weights,
                    double min_weight = 1e-3);

}  // namespace skinstream::synth
