#include "core/offline/vertex_part_weights.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <utility>

#include "core/geometry/triangle_bvh.h"
#include "core/geometry/triangle_mesh.h"
#include "core/precondition.h"

namespace skinstream {
namespace {

constexpr Precondition require_vertex_weights{"vertex part weights"};

// Below this, an interpolated weight counts as zero (a vertex on an edge or a vertex of the
// triangle gets exactly what its markers have, not a trace of the opposite marker).
constexpr double kZeroWeight = 1e-12;

void add_influence(std::vector<PartInfluence>& to, int part, double weight) {
  auto it = std::find_if(to.begin(), to.end(), [&](const PartInfluence& b) { return b.part == part; });
  if (it == to.end()) to.push_back({part, weight});
  else it->weight += weight;
}

// A vertex in a fold between two parts' skins (the armpit, the groin, the inner elbow) lies
// between its nearest triangle and one of another part, on the far side of it: the nearest
// triangle alone flips from one part to the other at the fold's middle, where the two are
// equally far. There both sides share the vertex, by inverse distance, fading out as the far
// side grows to kFoldRatio times the near one's distance, and as the two directions close from
// 120 degrees apart to 90 (beyond 90 the other triangle is beside the vertex, not across it).
// Shares below kMinFoldShare fade to nothing (the same continuous ramp keeps one half at the
// middle): past the head, hands and feet, far from every marker, the rule would otherwise hand
// thousands of vertices a trace of a distant part, each one more part to blend per frame.
constexpr double kFoldRatio = 3.0;
constexpr double kMinFoldShare = 0.05;

double fold_share(double near, double far, double cos_between) {
  const double ratio = far / near;
  if (!(ratio < kFoldRatio) || !(cos_between < 0.0)) return 0.0;
  const double across = std::min(1.0, -cos_between / 0.5);  // cos 120 degrees = -0.5
  const double share = near / (near + far) * (kFoldRatio - ratio) / (kFoldRatio - 1.0) * across;
  return share > kMinFoldShare ? 0.5 * (share - kMinFoldShare) / (0.5 - kMinFoldShare) : 0.0;
}

// Share of a marker's weight for one side's part that goes to the part across the joint, for a
// vertex `past` mm beyond the point up to which the marker speaks for its side (half at that
// point, none `half_width` before it, all `half_width` after). 0 width: a hard switch.
double joint_ramp(double past, double half_width) {
  if (!(half_width > 0.0)) return past > 0.0 ? 1.0 : 0.0;
  return std::clamp(0.5 + past / (2.0 * half_width), 0.0, 1.0);
}

bool same_influences(const std::vector<PartInfluence>& a, const std::vector<PartInfluence>& b) {
  if (a.size() != b.size()) return false;
  for (size_t k = 0; k < a.size(); ++k)
    if (a[k].part != b[k].part || std::abs(a[k].weight - b[k].weight) > 1e-9) return false;
  return true;
}

}  // namespace

VertexPartWeights vertex_part_weights(std::span<const Vec3> vertices, std::span<const Vec3> markers,
                                      std::span<const std::array<int, 3>> triangles, std::span<const int> part_member_offsets,
                                      std::span<const PartMember> part_members, std::span<const PartJoint> joints,
                                      std::span<const char> under_marker, bool blend_folds, double joint_blend_mm) {
  const int m = static_cast<int>(markers.size());
  require_vertex_weights(!triangles.empty(), "no marker-surface triangles");
  require_vertex_weights(!part_member_offsets.empty() && part_member_offsets.front() == 0 &&
              part_member_offsets.back() == static_cast<int>(part_members.size()),
          "part member offsets do not span the members");
  for (int i = 0; i < m; ++i) require_vertex_weights(markers[i].allFinite(), "marker " + std::to_string(i) + " is not finite");
  for (size_t j = 0; j < vertices.size(); ++j) require_vertex_weights(vertices[j].allFinite(), "vertex " + std::to_string(j) + " is not finite");
  for (size_t t = 0; t < triangles.size(); ++t)
    for (int v : triangles[t])
      require_vertex_weights(v >= 0 && v < m, "triangle " + std::to_string(t) + " refers to marker " + std::to_string(v) + " of " + std::to_string(m));

  // alpha rows per marker, sorted by part.
  const int part_count = static_cast<int>(part_member_offsets.size()) - 1;
  require_vertex_weights(joint_blend_mm >= 0.0 && std::isfinite(joint_blend_mm),
          "the joint blend width " + std::to_string(joint_blend_mm) + " mm is not a distance");
  require_vertex_weights(under_marker.empty() || under_marker.size() == vertices.size(),
          std::to_string(under_marker.size()) + " under-marker flags for " + std::to_string(vertices.size()) + " vertices");
  for (const PartJoint& joint : joints)
    require_vertex_weights(joint.first >= 0 && joint.first < part_count && joint.second >= 0 && joint.second < part_count &&
                joint.first != joint.second && joint.centre.allFinite() && joint.axis.allFinite(),
            "a joint names parts " + std::to_string(joint.first) + " and " + std::to_string(joint.second) + " of " +
                std::to_string(part_count) + " or is not finite");
  std::vector<std::vector<PartInfluence>> alpha(m);
  for (int p = 0; p < part_count; ++p) {
    require_vertex_weights(part_member_offsets[p] <= part_member_offsets[p + 1], "part member offsets decrease at part " + std::to_string(p));
    for (int k = part_member_offsets[p]; k < part_member_offsets[p + 1]; ++k) {
      const PartMember& member = part_members[k];
      require_vertex_weights(member.marker >= 0 && member.marker < m,
              "part " + std::to_string(p) + " names marker " + std::to_string(member.marker) + " of " + std::to_string(m));
      require_vertex_weights(member.weight >= 0.0 && std::isfinite(member.weight),
              "marker " + std::to_string(member.marker) + " has weight " + std::to_string(member.weight) + " in part " + std::to_string(p));
      if (member.weight > 0.0) alpha[member.marker].push_back({p, member.weight});
    }
  }

  const std::vector<Triangle> tris(triangles.begin(), triangles.end());
  const std::vector<Vec3> points(markers.begin(), markers.end());
  const TriangleBvh bvh(points, tris);

  // Fold blending: each triangle's main part (largest summed alpha of its markers) and a sphere
  // around it, to skip triangles that cannot be near enough.
  std::vector<int> main_part(tris.size(), -1);
  std::vector<Vec3> centre(tris.size());
  std::vector<double> radius(tris.size());
  if (blend_folds) {
    std::vector<PartInfluence> sum;
    for (size_t u = 0; u < tris.size(); ++u) {
      sum.clear();
      for (int k = 0; k < 3; ++k)
        for (const PartInfluence& a : alpha[tris[u][k]]) add_influence(sum, a.part, a.weight);
      double most = 0.0;
      for (const PartInfluence& b : sum)
        if (b.weight > most || (b.weight == most && b.part < main_part[u])) {
          most = b.weight;
          main_part[u] = b.part;
        }
      centre[u] = (points[tris[u][0]] + points[tris[u][1]] + points[tris[u][2]]) / 3.0;
      radius[u] = 0.0;
      for (int k = 0; k < 3; ++k) radius[u] = std::max(radius[u], (points[tris[u][k]] - centre[u]).norm());
    }
  }

  // A vertex's weights from (triangle, share) sides, sorted by part and normalised.
  std::vector<PartInfluence> row;
  auto weigh = [&](size_t j, bool keep_markers, int t, const std::array<std::pair<int, double>, 2>& sides,
                   std::vector<PartInfluence>& blend) {
    blend.clear();
    for (const auto& [side, share] : sides) {
      if (side < 0 || !(share > 0.0)) continue;
      const Triangle& tri = tris[side];
      Vec3 bary;
      closest_point_on_triangle(vertices[j], points[tri[0]], points[tri[1]], points[tri[2]], &bary);
      for (int k = 0; k < 3; ++k) {
        if (!(bary[k] > kZeroWeight)) continue;
        row = alpha[tri[k]];
        if (!keep_markers) {
          // Across a joint, a marker speaks for its side's part up to the joint's plane, or up to
          // its own height when it lies past the plane; what it gives that part further on goes
          // to the part across, over a ramp joint_blend_mm either side of that threshold.
          for (const PartJoint& joint : joints) {
            const double vertex_side = joint.side(vertices[j]), marker_side = joint.side(points[tri[k]]);
            const double to_second = joint_ramp(vertex_side - std::max(marker_side, 0.0), joint_blend_mm);
            const double to_first = joint_ramp(std::min(marker_side, 0.0) - vertex_side, joint_blend_mm);
            double first_to_second = 0.0, second_to_first = 0.0;
            for (PartInfluence& b : row) {
              if (b.part == joint.first) {
                first_to_second = b.weight * to_second;
                b.weight -= first_to_second;
              } else if (b.part == joint.second) {
                second_to_first = b.weight * to_first;
                b.weight -= second_to_first;
              }
            }
            if (first_to_second > 0.0) add_influence(row, joint.second, first_to_second);
            if (second_to_first > 0.0) add_influence(row, joint.first, second_to_first);
            std::erase_if(row, [](const PartInfluence& b) { return !(b.weight > 0.0); });
          }
        }
        for (const PartInfluence& a : row) add_influence(blend, a.part, share * bary[k] * a.weight);
      }
    }
    std::erase_if(blend, [](const PartInfluence& b) { return !(b.weight > kZeroWeight); });
    require_vertex_weights(!blend.empty(), "the markers of triangle " + std::to_string(t) + " belong to no part");
    std::sort(blend.begin(), blend.end(), [](const PartInfluence& a, const PartInfluence& b) { return a.part < b.part; });
    normalize_influences(blend);
  };

  VertexPartWeights out;
  out.vertex_influence_offsets.reserve(vertices.size() + 1);
  out.in_fold.assign(vertices.size(), 0);
  std::vector<PartInfluence> blend, nearest_only;
  for (size_t j = 0; j < vertices.size(); ++j) {
    const bool keep_markers = !under_marker.empty() && under_marker[j];
    int t = -1;
    Vec3 near_point;
    const double near = bvh.closest(vertices[j], &t, &near_point);
    // (triangle, share): the nearest alone, or with the other side of a fold.
    std::array<std::pair<int, double>, 2> sides{{{t, 1.0}, {-1, 0.0}}};
    if (blend_folds && !keep_markers && near > 0.0) {
      const Vec3 towards_near = (near_point - vertices[j]) / near;
      for (size_t u = 0; u < tris.size(); ++u) {
        if (main_part[u] == main_part[t] || (centre[u] - vertices[j]).norm() - radius[u] >= kFoldRatio * near) continue;
        const Vec3 q = closest_point_on_triangle(vertices[j], points[tris[u][0]], points[tris[u][1]], points[tris[u][2]]);
        const double far = (q - vertices[j]).norm();
        const double share = fold_share(near, far, towards_near.dot((q - vertices[j]) / far));
        if (share > sides[1].second) sides[1] = {static_cast<int>(u), share};
      }
      sides[0].second = 1.0 - sides[1].second;
    }
    weigh(j, keep_markers, t, sides, blend);
    // Where the joints' split leaves both sides with the same weights, the blend changed nothing.
    if (sides[1].second > 0.0) {
      weigh(j, keep_markers, t, {{{t, 1.0}, {-1, 0.0}}}, nearest_only);
      out.in_fold[j] = !same_influences(blend, nearest_only);
    }
    out.vertex_influences.insert(out.vertex_influences.end(), blend.begin(), blend.end());
    out.vertex_influence_offsets.push_back(static_cast<int>(out.vertex_influences.size()));
  }
  return out;
}

std::vector<char> vertices_under_markers(std::span<const Vec3> vertices, std::span<const std::array<int, 3>> faces,
                                         std::span<const Vec3> markers) {
  require_vertex_weights(!faces.empty(), "the mesh has no faces");
  const int v = static_cast<int>(vertices.size());
  for (size_t f = 0; f < faces.size(); ++f)
    for (int corner : faces[f])
      require_vertex_weights(corner >= 0 && corner < v, "face " + std::to_string(f) + " refers to vertex " + std::to_string(corner) + " of " + std::to_string(v));
  const std::vector<Triangle> tris(faces.begin(), faces.end());
  const std::vector<Vec3> points(vertices.begin(), vertices.end());
  const TriangleBvh bvh(points, tris);
  std::vector<char> under(vertices.size(), 0);
  for (const Vec3& marker : markers) {
    int face = -1;
    bvh.closest(marker, &face);
    if (face >= 0)
      for (int corner : faces[face]) under[corner] = 1;
  }
  return under;
}

}  // namespace skinstream
