#include "core/deform/segment_skeleton.h"

#include <cmath>

namespace skinstream {

std::string SegmentSkeleton::validate(int expected_markers, int part_count) const {
  if (segments.empty()) return "a skeleton with no segments";
  for (int s = 0; s < segment_count(); ++s) {
    const SkeletonSegment& segment = segments[s];
    if ((s == 0) != (segment.parent < 0)) return "skeleton segment " + std::to_string(s) + " (" + segment.name + "): only the first segment is a root";
    if (segment.parent >= s) return "skeleton segment " + segment.name + " comes before its parent";
    if (!segment.pivot.allFinite()) return "skeleton segment " + segment.name + " has a non-finite pivot";
  }
  if (marker_count() != expected_markers)
    return "skeleton weights for " + std::to_string(marker_count()) + " markers, the subject has " + std::to_string(expected_markers);
  if (marker_weight_offsets.front() != 0 || marker_weight_offsets.back() != static_cast<int>(marker_weights.size()))
    return "skeleton marker weight offsets do not span the weights";
  for (int i = 0; i < marker_count(); ++i) {
    const int begin = marker_weight_offsets[i], end = marker_weight_offsets[i + 1];
    if (end <= begin) return "skeleton: marker " + std::to_string(i) + " has no segment weights";
    double sum = 0.0;
    for (int k = begin; k < end; ++k) {
      const SegmentWeight& w = marker_weights[k];
      if (w.segment < 0 || w.segment >= segment_count()) return "skeleton: marker " + std::to_string(i) + " names segment " + std::to_string(w.segment);
      if (!(w.weight > 0.0) || !std::isfinite(w.weight)) return "skeleton: marker " + std::to_string(i) + " has a weight that is not positive and finite";
      sum += w.weight;
    }
    if (std::abs(sum - 1.0) > 1e-6) return "skeleton: the weights of marker " + std::to_string(i) + " sum to " + std::to_string(sum);
  }
  if (static_cast<int>(part_segment.size()) != part_count)
    return "skeleton segments for " + std::to_string(part_segment.size()) + " parts, the model has " + std::to_string(part_count);
  for (int s : part_segment)
    if (s < 0 || s >= segment_count()) return "skeleton: a part names segment " + std::to_string(s);
  return {};
}

}  // namespace skinstream
