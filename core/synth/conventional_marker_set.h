#pragma once
// The "conventional motion capture" of the paper's Figure 8 made from the synthetic body: up to 15
// body segments (pelvis, thorax, head, and per side upper arm, forearm, hand, thigh, shank,
// foot), each driven by about three markers picked from the dense set the way a technician
// places them on bony landmarks (the markers of that segment that move least relative to its
// bone over a training take, spread apart), and the skin weights of the mesh summed per
// segment for linear blend skinning.

#include <string>
#include <vector>

#include "core/baselines/segment_skinning.h"
#include "core/body/body.h"
#include "core/synth/synth_capture.h"

namespace skinstream::synth {

struct ConventionalMarkerSet {
  std::vector<std::string> segment_names;
  std::vector<int> bone_segment;  // per bone of the skeleton
  SegmentSkinningModel skinning;  // markers in the training capture's truth order
  int marker_count() const;
};

// training: a synthetic take of the body (its truth and poses are used); weights: the skin
// weights of the mesh the skinning will move (the body's, or its subdivision's).
// Segments with fewer than `per_segment` markers are dropped (their bones ride with the parent
// segment); throws std::invalid_argument when the pelvis has too few.
ConventionalMarkerSet choose_conventional_markers(const Body& body, const SynthCapture& training,
                                                  const SkinWeights& weights, int per_segment = 3);

// The same segments and markers with skin weights a rigging tool would compute from the rest
// mesh and skeleton alone (bone heat, core/baselines/bone_heat_weights.h) instead of the body's
// own weights, the ones the synthetic truth is skinned with. `body`: the mesh to be skinned (the
// subdivided body when the takes are subdivided).
SegmentSkinningModel bone_heat_skinning(const Body& body, const ConventionalMarkerSet& set);

}  // namespace skinstream::synth
