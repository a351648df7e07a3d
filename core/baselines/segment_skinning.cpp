#include "core/baselines/segment_skinning.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "core/absolute_orientation.h"

namespace skinstream {

SegmentSkinning::SegmentSkinning(SegmentSkinningModel model, std::span<const Vec3> reference_markers,
                                 std::span<const Vec3> reference_vertices)
    : model_(std::move(model)),
      reference_markers_(reference_markers.begin(), reference_markers.end()),
      reference_vertices_(reference_vertices.begin(), reference_vertices.end()) {
  const int segments = static_cast<int>(model_.segment_markers.size());
  size_t largest = 0;
  for (int s = 0; s < segments; ++s) {
    const auto& markers = model_.segment_markers[s];
    if (markers.size() < 3) throw std::invalid_argument("segment " + std::to_string(s) + " has fewer than 3 markers");
    for (int m : markers)
      if (m < 0 || m >= marker_count()) throw std::invalid_argument("segment marker index out of range");
    largest = std::max(largest, markers.size());
  }
  if (model_.vertex_weight_offsets.size() != reference_vertices_.size() + 1)
    throw std::invalid_argument("segment weights do not cover the vertices");
  for (int v = 0; v < vertex_count(); ++v) {
    double sum = 0.0;
    for (int k = model_.vertex_weight_offsets[v]; k < model_.vertex_weight_offsets[v + 1]; ++k) {
      if (model_.vertex_weights[k].part < 0 || model_.vertex_weights[k].part >= segments)
        throw std::invalid_argument("vertex weight on an unknown segment");
      sum += model_.vertex_weights[k].weight;
    }
    if (std::abs(sum - 1.0) > 1e-6) throw std::invalid_argument("vertex " + std::to_string(v) + " weights do not sum to 1");
  }
  rotation_.assign(segments, Eigen::Matrix3d::Identity());
  translation_.assign(segments, Vec3::Zero());
  source_.resize(largest);
  target_.resize(largest);
}

bool SegmentSkinning::solve(std::span<const Vec3> markers) {
  if (static_cast<int>(markers.size()) != marker_count()) return false;
  for (const auto& set : model_.segment_markers)
    for (int m : set)
      if (!is_present(markers[m])) return false;
  for (size_t s = 0; s < model_.segment_markers.size(); ++s) {
    const auto& set = model_.segment_markers[s];
    for (size_t k = 0; k < set.size(); ++k) {
      source_[k] = reference_markers_[set[k]];
      target_[k] = markers[set[k]];
    }
    RigidTransform fit;
    fit_rigid(std::span<const Vec3>(source_.data(), set.size()), std::span<const Vec3>(target_.data(), set.size()), fit);
    rotation_[s] = fit.rotation;
    translation_[s] = fit.translation;
  }
  return true;
}

void SegmentSkinning::deform(std::span<float> positions) const {
  for (int v = 0; v < vertex_count(); ++v) {
    Vec3 sum = Vec3::Zero();
    for (int k = model_.vertex_weight_offsets[v]; k < model_.vertex_weight_offsets[v + 1]; ++k) {
      const PartInfluence& w = model_.vertex_weights[k];
      sum += w.weight * (rotation_[w.part] * reference_vertices_[v] + translation_[w.part]);
    }
    for (int c = 0; c < 3; ++c) positions[static_cast<size_t>(v) * 3 + c] = static_cast<float>(sum[c]);
  }
}

}  // namespace skinstream
