#pragma once
// The skeleton a sparse marker set drives the body with. With 37-60 markers most near-rigid
// parts have too few markers of their own for the paper's per-part Horn fit (a thigh carries
// two), so the body is posed instead as a chain of segments fitted to all markers at once: a
// segment's rotation is pinned down by the markers of its neighbours through the joints it
// shares with them. Each part of the deformation model then takes its rigid transform from its
// segment, and eqs. 6-7 resolve what the segment's motion leaves at the part's own markers.
//
// Everything is in the reference pose (the subject's reference frame, mm): a segment turns
// about its pivot, and a marker follows the weighted average of its segments' motions (linear
// blend skinning of the marker's reference position, weights from the fitted template's skin
// weights where the marker sits).

#include <string>
#include <vector>

#include "core/capture.h"

namespace skinstream {

struct SkeletonSegment {
  std::string name;
  int parent = -1;            // index of the parent segment (before this one); -1 for the root
  Vec3 pivot = Vec3::Zero();  // the joint it turns about, reference pose, mm
};

// A marker's (or a vertex's) share of a segment's motion.
struct SegmentWeight {
  int segment = 0;
  double weight = 0.0;
};

struct SegmentSkeleton {
  std::vector<SkeletonSegment> segments;  // the root first; parents before their children
  // Each marker's weights over the segments (CSR by marker, each marker's sum 1).
  std::vector<int> marker_weight_offsets{0};
  std::vector<SegmentWeight> marker_weights;
  // Per part of the deformation model: the segment whose motion is the part's rigid transform.
  std::vector<int> part_segment;

  bool empty() const { return segments.empty(); }
  int segment_count() const { return static_cast<int>(segments.size()); }
  int marker_count() const { return static_cast<int>(marker_weight_offsets.size()) - 1; }

  // Empty when consistent with `marker_count` markers and `part_count` parts; otherwise what is
  // wrong, in one line (a parent after its child, a weight that is not positive and finite, a
  // marker whose weights do not sum to 1, a part without a segment...).
  std::string validate(int marker_count, int part_count) const;
};

}  // namespace skinstream
