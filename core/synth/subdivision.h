#pragma once
// One step of midpoint quad subdivision: every edge gets its midpoint, every face its
// centroid, and each n-gon becomes n quads. The refined surface lies on the original bilinear
// patches (no smoothing, no shrinkage). The MakeHuman body (13,380 vertices, 13,378 quads)
// becomes about 53,500 vertices. Skin weights of a new vertex are the average of the weights
// of the vertices it averages (so a part skinned rigidly to one bone stays rigid, and the refined
// skinned surface stays within a fraction of a millimetre of the refined coarse one elsewhere).
#include <vector>

#include "core/body/body.h"

namespace skinstream::synth {

// `parent_face` (optional) receives, for each new face, the index of the face it came from.
// The first body.vertex_count() vertices keep their index. Throws like validate().
Body subdivide(const Body& body, std::vector<int>* parent_face = nullptr);

}  // namespace skinstream::synth
