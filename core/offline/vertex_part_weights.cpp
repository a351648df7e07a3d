#include "core/offline/vertex_part_weights.h"

#include <algorithm>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>

#include "core/synth/body.h"
#include "core/synth/bvh.h"

namespace skinstream {
namespace {

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("vertex part weights: " + what);
}

// Below this, an interpolated weight counts as zero (a vertex on an edge or a vertex of the
// triangle gets exactly what its markers have, not a trace of the opposite marker).
constexpr double kZeroWeight = 1e-12;

}  // namespace

VertexPartWeights vertex_part_weights(std::span<const Vec3> vertices, std::span<const Vec3> markers,
                                      std::span<const std::array<int, 3>> triangles, std::span<const int> part_member_offsets,
                                      std::span<const PartMember> part_members) {
  const int m = static_cast<int>(markers.size());
  require(!triangles.empty(), "no marker-surface triangles");
  require(!part_member_offsets.empty() && part_member_offsets.front() == 0 &&
              part_member_offsets.back() == static_cast<int>(part_members.size()),
          "part member offsets do not span the members");
  for (int i = 0; i < m; ++i) require(markers[i].allFinite(), "marker " + std::to_string(i) + " is not finite");
  for (size_t j = 0; j < vertices.size(); ++j) require(vertices[j].allFinite(), "vertex " + std::to_string(j) + " is not finite");
  for (size_t t = 0; t < triangles.size(); ++t)
    for (int v : triangles[t])
      require(v >= 0 && v < m, "triangle " + std::to_string(t) + " refers to marker " + std::to_string(v) + " of " + std::to_string(m));

  // alpha rows per marker, sorted by part.
  const int part_count = static_cast<int>(part_member_offsets.size()) - 1;
  std::vector<std::vector<PartInfluence>> alpha(m);
  for (int p = 0; p < part_count; ++p) {
    require(part_member_offsets[p] <= part_member_offsets[p + 1], "part member offsets decrease at part " + std::to_string(p));
    for (int k = part_member_offsets[p]; k < part_member_offsets[p + 1]; ++k) {
      const PartMember& member = part_members[k];
      require(member.marker >= 0 && member.marker < m,
              "part " + std::to_string(p) + " names marker " + std::to_string(member.marker) + " of " + std::to_string(m));
      require(member.weight >= 0.0 && std::isfinite(member.weight),
              "marker " + std::to_string(member.marker) + " has weight " + std::to_string(member.weight) + " in part " + std::to_string(p));
      if (member.weight > 0.0) alpha[member.marker].push_back({p, member.weight});
    }
  }

  const std::vector<synth::Triangle> tris(triangles.begin(), triangles.end());
  const std::vector<Vec3> points(markers.begin(), markers.end());
  const synth::TriangleBvh bvh(points, tris);

  VertexPartWeights out;
  out.vertex_influence_offsets.reserve(vertices.size() + 1);
  std::vector<PartInfluence> blend;
  for (size_t j = 0; j < vertices.size(); ++j) {
    int t = -1;
    bvh.closest(vertices[j], &t);
    const synth::Triangle& tri = tris[t];
    Vec3 bary;
    synth::closest_point_on_triangle(vertices[j], points[tri[0]], points[tri[1]], points[tri[2]], &bary);
    blend.clear();
    for (int k = 0; k < 3; ++k) {
      if (!(bary[k] > kZeroWeight)) continue;
      for (const PartInfluence& a : alpha[tri[k]]) {
        auto it = std::find_if(blend.begin(), blend.end(), [&](const PartInfluence& b) { return b.part == a.part; });
        if (it == blend.end()) blend.push_back({a.part, bary[k] * a.weight});
        else it->weight += bary[k] * a.weight;
      }
    }
    std::erase_if(blend, [](const PartInfluence& b) { return !(b.weight > kZeroWeight); });
    require(!blend.empty(), "the markers of triangle " + std::to_string(t) + " belong to no part");
    std::sort(blend.begin(), blend.end(), [](const PartInfluence& a, const PartInfluence& b) { return a.part < b.part; });
    normalize_influences(blend);
    out.vertex_influences.insert(out.vertex_influences.end(), blend.begin(), blend.end());
    out.vertex_influence_offsets.push_back(static_cast<int>(out.vertex_influences.size()));
  }
  return out;
}

}  // namespace skinstream
