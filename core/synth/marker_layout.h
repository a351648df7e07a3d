#pragma once
// Where the markers go: about 350 points spread over the skin roughly 4-5 cm apart (Park &
// Hodgins drew a grid on the subject), plus extra ones where more resolution is needed - around
// the tip of each elbow and on the lower part of each shoulder blade.
//
// The grid is a farthest-point sampling by geodesic distance (Dijkstra on the mesh edges) over
// the trunk and limbs (not head, neck, hands or feet), started from the extra markers, so the
// count is exact and the spacing as even as the count allows; the trunk gets a slightly denser
// grid, forearms and lower legs a sparser one. Each marker sits on one triangle (barycentric), near the
// chosen vertex. Names are <region>_<n>, e.g. abdomen_12, chest_3, elbow_L_2, thigh_R_5, scapula_R_1; the
// region comes from the dominant bone at the marker (with front/back for the trunk and elbow or
// knee near those joints).
#include <cstdint>
#include <string>
#include <vector>

#include "core/body/anatomy.h"
#include "core/body/body.h"

namespace skinstream::synth {

struct MarkerSite {
  std::string name;
  std::string region;
  int triangle = -1;  // index into the surface's triangles
  Vec3 barycentric = Vec3::Zero();
  Vec3 rest_position = Vec3::Zero();  // on the rest surface (the marker sits offset along the normal)
  Vec3 rest_normal = Vec3::Zero();    // triangle normal, rest
  int dominant_bone = -1;             // of the mesh vertex the marker was placed at
  bool extra = false;                 // an elbow or shoulder-blade marker
};

struct LayoutOptions {
  int count = 350;              // total, extras included
  int elbow_extras = 3;         // per elbow
  int scapula_extras = 2;       // per shoulder blade
  double trunk_spacing = 0.9;   // trunk grid spacing relative to upper arms' and thighs'
  double distal_spacing = 1.4;  // forearm and lower-leg spacing relative to upper arms' and thighs'
  double jitter = 0.06;         // relative randomness of the sampling order (varies layouts by seed)
};

// Lays markers on the surface (rest, triangles, weights) of a body with that skeleton.
// Throws std::invalid_argument for a count below extras + 1 or above the candidate vertices.
std::vector<MarkerSite> layout_markers(const std::vector<Vec3>& rest, const std::vector<Triangle>& triangles,
                                       const SkinWeights& weights, const Skeleton& skeleton,
                                       const Anatomy& anatomy, const LayoutOptions& options, uint64_t seed);

// The region name of a point of the rest surface (no side suffix for the trunk).
std::string marker_region(const Skeleton& skeleton, const Anatomy& anatomy, int dominant_bone,
                          const Vec3& rest_position, const Vec3& rest_normal);

}  // namespace skinstream::synth
