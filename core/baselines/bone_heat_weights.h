#pragma once
// Skin weights from the mesh and its skeleton alone: the bone heat of Baran & Popović 2007
// ("Automatic rigging and animation of 3D characters", section 4), the method behind Blender's
// "automatic weights". Each group of bones (a body segment) heats the surface: at equilibrium
//   (-Laplacian + H) w_g = H p_g,
// where the Laplacian is the cotangent one divided by each vertex's area (a third of its
// triangles'), H is diagonal with H_jj = heat_constant / d_j^2 for the distance d_j from vertex j
// to its nearest bone seen from it (the segment to the bone's closest point crosses no triangle),
// and p_g,j is 1 when that bone belongs to group g (shared equally between bones equally near).
// Published constants: heat_constant = 1 (Blender's too). A vertex that sees no bone takes its
// nearest one anyway, so every connected piece of the surface is anchored. Nothing here looks at
// any motion: the weights are what a rigging tool would give the rest mesh.

#include <vector>

#include "core/baselines/segment_skinning.h"
#include "core/geometry/triangle_mesh.h"

namespace skinstream {

struct HeatBone {
  Vec3 head = Vec3::Zero(), tail = Vec3::Zero();  // rest pose, same units as the mesh
  int group = 0;                                 // the segment that moves it
};

struct BoneHeatOptions {
  double heat_constant = 1.0;
  double min_weight = 0.01;   // smaller weights are dropped and the rest renormalised
  double surface_skip = 0.1;  // visibility: triangle hits this close to the vertex are its own
};

// Per vertex, the weight of each group (CSR, each vertex sums to 1), in the form SegmentSkinning
// takes. Throws std::invalid_argument for no bones, a group outside [0, group_count), or a
// triangle index out of range.
void bone_heat_weights(const std::vector<Vec3>& vertices, const std::vector<Triangle>& triangles,
                       const std::vector<HeatBone>& bones, int group_count, const BoneHeatOptions& options,
                       std::vector<int>& out_offsets, std::vector<PartInfluence>& out_weights);

}  // namespace skinstream
