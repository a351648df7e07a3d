#pragma once
// Soft tissue that jiggles and lags: each fleshy region (belly, chest, buttocks, thighs, calves,
// backs of the upper arms, flanks) is a damped spring hung on a bone. The spring is driven by
// the acceleration of its anchor point on the skeleton: when the bone accelerates the tissue
// lags behind, then overshoots and rings down. The region's skin is displaced by the spring's
// offset times the region weight, softly limited to max_mm.
//
//   u'' = -w^2 u - 2 zeta w u' - gain * a_anchor,   w = 2 pi frequency
#include <string>
#include <vector>

#include "core/body/anatomy.h"
#include "core/synth/body_region.h"

namespace skinstream::synth {

struct JiggleRegion {
  std::string name;
  Region region;
  int anchor_bone = -1;
  Vec3 anchor_point = Vec3::Zero();  // rest, mm; rigidly attached to anchor_bone
  double frequency_hz = 4.0;
  double damping_ratio = 0.2;
  double gain = 1.0;
  double max_mm = 15.0;
};

std::vector<JiggleRegion> standard_jiggle(const Body& body, const Anatomy& anatomy);

// Offset (mm, world axes) of every region at every frame, starting at rest. Throws
// std::invalid_argument for a rate <= 0, substeps < 1 or an anchor bone out of range.
std::vector<std::vector<Vec3>> simulate_jiggle(const std::vector<JiggleRegion>& regions,
                                               const std::vector<BoneTransforms>& frames, double rate_hz,
                                               int substeps = 4);

}  // namespace skinstream::synth
