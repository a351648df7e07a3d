#include "core/offline/marker_part_weights.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include "core/absolute_orientation.h"
#include "core/offline/marker_surface_builder.h"
#include "core/offline/part_motions.h"
#include "core/precondition.h"

namespace skinstream {
namespace {

constexpr Precondition require_marker_weights{"marker part weights"};

// Weight given to a marker added to a part only to reach min_members, at least (before the
// marker's row is renormalised): the part must not get a zero weight.
constexpr double kAddedMemberFloor = 0.01;

using Row = std::vector<std::pair<int, double>>;  // (part, weight), sorted by part

// Per marker, the parts its weights are chosen among: those of the triangles of every marker
// within `rings` marker-surface edges of it (itself alone at 0), sorted.
std::vector<std::vector<int>> candidate_parts(std::span<const std::array<int, 3>> triangles,
                                              const std::vector<std::vector<int>>& marker_parts, int rings) {
  const int m = static_cast<int>(marker_parts.size());
  const std::vector<std::vector<int>> neighbours = triangle_neighbours(triangles, m);
  std::vector<std::vector<int>> out(m);
  std::vector<int> seen(m, -1), frontier, next;
  for (int i = 0; i < m; ++i) {
    frontier.assign(1, i);
    seen[i] = i;
    out[i] = marker_parts[i];
    for (int ring = 0; ring < rings && !frontier.empty(); ++ring) {
      next.clear();
      for (int a : frontier)
        for (int b : neighbours[a])
          if (seen[b] != i) {
            seen[b] = i;
            next.push_back(b);
            out[i].insert(out[i].end(), marker_parts[b].begin(), marker_parts[b].end());
          }
      frontier.swap(next);
    }
    std::sort(out[i].begin(), out[i].end());
    out[i].erase(std::unique(out[i].begin(), out[i].end()), out[i].end());
  }
  return out;
}

}  // namespace

double MarkerPartWeights::weight(int marker, int part) const {
  if (part < 0 || part + 1 >= static_cast<int>(part_member_offsets.size())) return 0.0;
  for (int k = part_member_offsets[part]; k < part_member_offsets[part + 1]; ++k)
    if (part_members[k].marker == marker) return part_members[k].weight;
  return 0.0;
}

MarkerPartWeights marker_part_weights(std::span<const Vec3> reference, std::span<const std::array<int, 3>> triangles,
                                      std::span<const int> triangle_part, int part_count, std::span<const Vec3> positions,
                                      int frame_count, const MarkerWeightOptions& options) {
  const int m = static_cast<int>(reference.size());
  require_marker_weights(m > 0, "no markers");
  require_marker_weights(part_count >= 1, "no parts");
  require_marker_weights(frame_count > 0, "no frames");
  require_marker_weights(triangle_part.size() == triangles.size(),
          std::to_string(triangle_part.size()) + " part indices for " + std::to_string(triangles.size()) + " triangles");
  require_marker_weights(positions.size() == static_cast<size_t>(frame_count) * m,
          std::to_string(positions.size()) + " positions for " + std::to_string(frame_count) + " frames of " + std::to_string(m) + " markers");
  require_marker_weights(options.threshold >= 0.0 && options.threshold < 1.0, "threshold must be in [0, 1)");
  require_marker_weights(options.sigma_floor_mm > 0.0 && std::isfinite(options.sigma_floor_mm), "sigma_floor_mm must be > 0");
  require_marker_weights(options.min_members >= 1 && options.min_members <= m, "min_members must be in [1, marker count]");
  require_marker_weights(options.boundary_rings >= 0, "boundary_rings must be >= 0");
  std::vector<std::vector<int>> part_markers(part_count);  // markers of the part's triangles
  std::vector<std::vector<int>> marker_parts(m);           // parts of the marker's triangles
  for (size_t t = 0; t < triangles.size(); ++t) {
    const int p = triangle_part[t];
    require_marker_weights(p >= 0 && p < part_count, "triangle " + std::to_string(t) + " is in part " + std::to_string(p) + " of " + std::to_string(part_count));
    for (int v : triangles[t]) {
      require_marker_weights(v >= 0 && v < m, "triangle " + std::to_string(t) + " refers to marker " + std::to_string(v) + " of " + std::to_string(m));
      part_markers[p].push_back(v);
      marker_parts[v].push_back(p);
    }
  }
  for (auto* lists : {&part_markers, &marker_parts})
    for (auto& l : *lists) {
      std::sort(l.begin(), l.end());
      l.erase(std::unique(l.begin(), l.end()), l.end());
    }
  for (int p = 0; p < part_count; ++p) require_marker_weights(!part_markers[p].empty(), "part " + std::to_string(p) + " has no triangle");
  for (int i = 0; i < m; ++i) require_marker_weights(reference[i].allFinite(), "reference marker " + std::to_string(i) + " is not finite");
  for (size_t k = 0; k < positions.size(); ++k)
    require_marker_weights(positions[k].allFinite(), "marker " + std::to_string(k % m) + " is not finite at frame " + std::to_string(k / m));

  MarkerPartWeights out;
  out.inside_markers.assign(part_count, 0);
  for (int i = 0; i < m; ++i)
    if (marker_parts[i].size() == 1) ++out.inside_markers[marker_parts[i][0]];
  const std::vector<std::vector<int>> candidates = candidate_parts(triangles, marker_parts, options.boundary_rings);
  for (int i = 0; i < m; ++i) out.boundary_markers += candidates[i].size() != 1;

  // Each part's rigid motion per frame from its inside markers, and its sigma.
  std::vector<std::vector<int>> fitted(part_count);
  for (int p = 0; p < part_count; ++p) {
    for (int i : part_markers[p])
      if (marker_parts[i].size() == 1) fitted[p].push_back(i);
    if (fitted[p].size() < 3) fitted[p] = part_markers[p];  // too few inside markers to pin a rotation
  }
  const std::vector<RigidTransform> motion = fit_part_motions(reference, fitted, positions, frame_count);
  out.part_sigma_mm.assign(part_count, options.sigma_floor_mm);
  for (int p = 0; p < part_count; ++p) {
    double sum = 0.0;
    for (int f = 0; f < frame_count; ++f) {
      const RigidTransform& t = motion[static_cast<size_t>(p) * frame_count + f];
      for (int i : fitted[p]) sum += (t.apply(reference[i]) - positions[static_cast<size_t>(f) * m + i]).squaredNorm();
    }
    out.part_sigma_mm[p] = std::max(options.sigma_floor_mm, std::sqrt(sum / (fitted[p].size() * frame_count)));
  }

  // Normalised Gaussian likelihoods of marker i over `parts` (log domain: no underflow).
  auto likelihoods = [&](int i, const std::vector<int>& parts) {
    Row row;
    double best = -std::numeric_limits<double>::infinity();
    for (int p : parts) {
      double sum = 0.0;
      for (int f = 0; f < frame_count; ++f)
        sum += (motion[static_cast<size_t>(p) * frame_count + f].apply(reference[i]) - positions[static_cast<size_t>(f) * m + i]).squaredNorm();
      const double log_l = -(sum / frame_count) / (2.0 * out.part_sigma_mm[p] * out.part_sigma_mm[p]);
      row.emplace_back(p, log_l);
      best = std::max(best, log_l);
    }
    double total = 0.0;
    for (auto& [p, w] : row) total += (w = std::exp(w - best));
    for (auto& [p, w] : row) w /= total;
    return row;
  };
  auto renormalise = [](Row& row) {
    double total = 0.0;
    for (const auto& [p, w] : row) total += w;
    for (auto& [p, w] : row) w /= total;
  };

  std::vector<int> all_parts(part_count);
  for (int p = 0; p < part_count; ++p) all_parts[p] = p;
  std::vector<Row> rows(m);
  std::vector<Row> unthresholded(m);
  for (int i = 0; i < m; ++i) {
    if (candidates[i].size() == 1) {
      rows[i] = {{candidates[i][0], 1.0}};
      continue;
    }
    unthresholded[i] = likelihoods(i, candidates[i].empty() ? all_parts : candidates[i]);
    const auto strongest = std::max_element(unthresholded[i].begin(), unthresholded[i].end(),
                                            [](const auto& a, const auto& b) { return a.second < b.second; });
    for (const auto& [p, w] : unthresholded[i])
      if (w > options.threshold || p == strongest->first) rows[i].emplace_back(p, w);  // the strongest always stays
    renormalise(rows[i]);
  }

  // Parts short of min_members get markers back: dropped ones of their own triangles first
  // (best likelihood), then the nearest markers in the reference pose.
  std::vector<int> members(part_count, 0);
  for (const Row& row : rows)
    for (const auto& [p, w] : row) ++members[p];
  auto is_member = [&](int i, int p) {
    return std::any_of(rows[i].begin(), rows[i].end(), [p](const auto& e) { return e.first == p; });
  };
  for (int p = 0; p < part_count; ++p) {
    if (members[p] >= options.min_members) continue;
    std::vector<std::pair<double, int>> candidates;  // (sort key, marker): smaller first
    for (int i : part_markers[p])
      if (!is_member(i, p))
        for (const auto& [q, w] : unthresholded[i])
          if (q == p) candidates.emplace_back(-w, i);
    std::sort(candidates.begin(), candidates.end());
    std::vector<std::pair<double, int>> nearest;
    for (int i = 0; i < m; ++i) {
      if (is_member(i, p) || std::binary_search(part_markers[p].begin(), part_markers[p].end(), i)) continue;
      double d = std::numeric_limits<double>::infinity();
      for (int j : part_markers[p]) d = std::min(d, (reference[i] - reference[j]).squaredNorm());
      nearest.emplace_back(d, i);
    }
    std::sort(nearest.begin(), nearest.end());
    candidates.insert(candidates.end(), nearest.begin(), nearest.end());
    for (const auto& [key, i] : candidates) {
      if (members[p] >= options.min_members) break;
      std::vector<int> parts;
      for (const auto& [q, w] : rows[i]) parts.push_back(q);
      parts.push_back(p);
      std::sort(parts.begin(), parts.end());
      Row row = likelihoods(i, parts);
      for (auto& [q, w] : row)
        if (q == p) w = std::max(w, kAddedMemberFloor);
      renormalise(row);
      rows[i] = std::move(row);
      ++members[p];
      ++out.markers_added_for_min_members;
    }
  }

  // Rows per marker -> CSR per part, members by marker.
  std::vector<std::vector<PartMember>> by_part(part_count);
  for (int i = 0; i < m; ++i)
    for (const auto& [p, w] : rows[i]) by_part[p].push_back({i, w});
  for (const auto& list : by_part) {
    out.part_members.insert(out.part_members.end(), list.begin(), list.end());
    out.part_member_offsets.push_back(static_cast<int>(out.part_members.size()));
  }
  return out;
}

}  // namespace skinstream
