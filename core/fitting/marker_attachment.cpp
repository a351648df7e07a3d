#include "core/fitting/marker_attachment.h"

#include <algorithm>

namespace skinstream {

Vec3 skin_point(const MarkerAttachment& a, std::span<const Vec3> vertices, std::span<const Triangle> triangles) {
  const Triangle& t = triangles[static_cast<size_t>(a.triangle)];
  return a.barycentric[0] * vertices[t[0]] + a.barycentric[1] * vertices[t[1]] + a.barycentric[2] * vertices[t[2]];
}

Vec3 attached_position(const MarkerAttachment& a, std::span<const Vec3> vertices, std::span<const Triangle> triangles) {
  const Triangle& t = triangles[static_cast<size_t>(a.triangle)];
  return skin_point(a, vertices, triangles) + a.offset_mm * triangle_normal(vertices[t[0]], vertices[t[1]], vertices[t[2]]);
}

void attachment_segment_weights(const MarkerAttachment& a, std::span<const Triangle> triangles,
                                const VertexSegmentWeights& vertex_weights, std::vector<SegmentWeight>& out) {
  const size_t first = out.size();
  const Triangle& t = triangles[static_cast<size_t>(a.triangle)];
  for (int corner = 0; corner < 3; ++corner) {
    const double b = a.barycentric[corner];
    if (b <= 0.0) continue;
    for (int k = vertex_weights.offsets[t[corner]]; k < vertex_weights.offsets[t[corner] + 1]; ++k) {
      const SegmentWeight& w = vertex_weights.weights[static_cast<size_t>(k)];
      auto found = std::find_if(out.begin() + static_cast<long>(first), out.end(),
                                [&](const SegmentWeight& o) { return o.segment == w.segment; });
      if (found == out.end()) out.push_back({w.segment, b * w.weight});
      else found->weight += b * w.weight;
    }
  }
  // Weights too small to matter are dropped (a marker is not moved by a segment it barely
  // touches), and the rest renormalised.
  double sum = 0.0;
  out.erase(std::remove_if(out.begin() + static_cast<long>(first), out.end(),
                           [](const SegmentWeight& w) { return w.weight < 1e-3; }),
            out.end());
  for (size_t k = first; k < out.size(); ++k) sum += out[k].weight;
  for (size_t k = first; k < out.size(); ++k) out[k].weight /= sum;
  std::sort(out.begin() + static_cast<long>(first), out.end(),
            [](const SegmentWeight& x, const SegmentWeight& y) { return x.segment < y.segment; });
}

}  // namespace skinstream
