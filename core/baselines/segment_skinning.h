#pragma once
// Conventional motion capture, the comparison of the paper's Figure 8: a sparse marker set of
// about three markers per body segment drives each segment rigidly (Horn's method, from the
// reference pose to the current frame) and linear blend skinning moves the detailed mesh with
// the segments. It cannot show bulging, breathing or jiggling: only what the segments carry.

#include <span>
#include <vector>

#include "core/capture.h"
#include "core/deform/vertex_blend.h"

namespace skinstream {

struct SegmentSkinningModel {
  std::vector<std::vector<int>> segment_markers;  // marker indices (subject order), >= 3 per segment
  std::vector<int> vertex_weight_offsets{0};      // CSR over vertices
  std::vector<PartInfluence> vertex_weights;      // part = segment; each vertex sums to 1
};

class SegmentSkinning {
 public:
  // reference_markers: every marker of the subject in the reference pose; reference_vertices:
  // the detailed mesh in the same pose. Throws std::invalid_argument for a segment with fewer
  // than 3 markers, an index out of range or weights that do not cover the vertices.
  SegmentSkinning(SegmentSkinningModel model, std::span<const Vec3> reference_markers,
                  std::span<const Vec3> reference_vertices);

  // Fits every segment; false (previous fit kept) for a wrong count or a missing marker of the set.
  bool solve(std::span<const Vec3> markers);
  // The skinned vertices at the solved frame, 3 floats each.
  void deform(std::span<float> positions) const;

  int vertex_count() const { return static_cast<int>(reference_vertices_.size()); }
  int marker_count() const { return static_cast<int>(reference_markers_.size()); }

 private:
  SegmentSkinningModel model_;
  std::vector<Vec3> reference_markers_;
  std::vector<Vec3> reference_vertices_;
  std::vector<Eigen::Matrix3d> rotation_;
  std::vector<Vec3> translation_;
  std::vector<Vec3> source_, target_;
};

}  // namespace skinstream
