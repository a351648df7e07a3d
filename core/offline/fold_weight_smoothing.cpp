#include "core/offline/fold_weight_smoothing.h"

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <queue>
#include <string>
#include <utility>
#include <vector>

#include "core/deform/mesh_edges.h"
#include "core/precondition.h"

namespace skinstream {
namespace {

constexpr Precondition require_smoothing{"fold weight smoothing"};

// A vertex's hold on its own weights when nothing else holds it (a piece of mesh in the fold with
// no vertex around it keeping its weights): small enough not to matter anywhere else.
constexpr double kSelfHold = 1e-6;

}  // namespace

int smooth_fold_weights(std::span<const Vec3> vertices, std::span<const std::array<int, 3>> faces,
                        std::span<const char> under_marker, int part_count, VertexPartWeights& weights,
                        const FoldSmoothingOptions& options) {
  require_smoothing(options.band_mm >= 0.0 && std::isfinite(options.band_mm), "band_mm must be >= 0");
  require_smoothing(options.band_pull >= 0.0 && std::isfinite(options.band_pull), "band_pull must be >= 0");
  require_smoothing(options.min_weight >= 0.0 && options.min_weight < 1.0, "min_weight must be in [0, 1)");
  const std::vector<int>& offsets = weights.vertex_influence_offsets;
  require_smoothing(!offsets.empty() && offsets.front() == 0 && offsets.back() == static_cast<int>(weights.vertex_influences.size()),
          "the influence offsets do not span the influences");
  const int v_count = static_cast<int>(offsets.size()) - 1;
  require_smoothing(vertices.size() == static_cast<size_t>(v_count),
          std::to_string(vertices.size()) + " vertices for the weights of " + std::to_string(v_count));
  for (int v = 0; v < v_count; ++v) require_smoothing(vertices[v].allFinite(), "vertex " + std::to_string(v) + " is not finite");
  require_smoothing(weights.in_fold.size() == static_cast<size_t>(v_count),
          std::to_string(weights.in_fold.size()) + " fold flags for " + std::to_string(v_count) + " vertices");
  require_smoothing(under_marker.empty() || under_marker.size() == static_cast<size_t>(v_count),
          std::to_string(under_marker.size()) + " under-marker flags for " + std::to_string(v_count) + " vertices");
  for (size_t f = 0; f < faces.size(); ++f)
    for (int c : faces[f])
      require_smoothing(c >= 0 && c < v_count, "face " + std::to_string(f) + " refers to vertex " + std::to_string(c) + " of " + std::to_string(v_count));
  for (const PartInfluence& b : weights.vertex_influences)
    require_smoothing(b.part >= 0 && b.part < part_count, "an influence names part " + std::to_string(b.part) + " of " + std::to_string(part_count));

  auto keeps = [&](int v) { return !under_marker.empty() && under_marker[v]; };
  // The fold's vertices, then the band around them: every vertex within band_mm of one along the
  // mesh's edges (Dijkstra from all of the fold's vertices; a vertex under a marker neither joins
  // nor passes the band on).
  // Each vertex's mesh neighbours, each once and in ascending order, with the edge's length.
  std::vector<std::vector<std::pair<int, double>>> edges(v_count);
  for (const auto& [a, b] : unique_edges(faces)) {
    const double length = (vertices[a] - vertices[b]).norm();
    edges[a].emplace_back(b, length);
    edges[b].emplace_back(a, length);
  }
  std::vector<char> smoothed(v_count, 0);
  std::vector<double> distance(v_count, std::numeric_limits<double>::infinity());
  std::priority_queue<std::pair<double, int>, std::vector<std::pair<double, int>>, std::greater<>> queue;
  for (int v = 0; v < v_count; ++v)
    if (weights.in_fold[v] && !keeps(v)) {
      distance[v] = 0.0;
      queue.emplace(0.0, v);
    }
  while (!queue.empty()) {
    const auto [d, v] = queue.top();
    queue.pop();
    if (d > distance[v]) continue;
    smoothed[v] = 1;
    for (const auto& [u, length] : edges[v])
      if (!keeps(u) && d + length <= options.band_mm && d + length < distance[u]) {
        distance[u] = d + length;
        queue.emplace(distance[u], u);
      }
  }
  std::vector<int> row_of(v_count, -1);
  int n = 0;
  for (int v = 0; v < v_count; ++v)
    if (smoothed[v]) row_of[v] = n++;
  if (n == 0) return 0;

  // The graph Laplacian (every mesh edge counts alike) over the smoothed vertices; the others
  // are fixed and move to the right-hand side, one column per part.
  std::vector<Eigen::Triplet<double>> entries;
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(n, part_count);
  auto add_weights = [&](int v, double scale, int to_row) {
    for (int k = offsets[v]; k < offsets[v + 1]; ++k)
      rhs(to_row, weights.vertex_influences[k].part) += scale * weights.vertex_influences[k].weight;
  };
  for (int v = 0; v < v_count; ++v) {
    if (!smoothed[v]) continue;
    const int i = row_of[v];
    for (const auto& [u, length] : edges[v]) {
      if (smoothed[u]) entries.emplace_back(i, row_of[u], -1.0);
      else add_weights(u, 1.0, i);
    }
    // A smoothed vertex is never under a marker, so its own flag says fold or band.
    const double hold = kSelfHold + (weights.in_fold[v] ? 0.0 : options.band_pull);
    entries.emplace_back(i, i, static_cast<double>(edges[v].size()) + hold);
    add_weights(v, hold, i);
  }
  Eigen::SparseMatrix<double> laplacian(n, n);
  laplacian.setFromTriplets(entries.begin(), entries.end());
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(laplacian);
  require_smoothing(solver.info() == Eigen::Success, "the fold's system could not be factored");
  const Eigen::MatrixXd solved = solver.solve(rhs);

  VertexPartWeights out;
  out.in_fold = std::move(weights.in_fold);
  out.vertex_influences.reserve(weights.vertex_influences.size());
  std::vector<PartInfluence> row;
  for (int v = 0; v < v_count; ++v) {
    if (!smoothed[v]) {
      out.vertex_influences.insert(out.vertex_influences.end(), weights.vertex_influences.begin() + offsets[v],
                                   weights.vertex_influences.begin() + offsets[v + 1]);
    } else {
      const auto w = solved.row(row_of[v]);
      row.clear();
      for (int p = 0; p < part_count; ++p)
        if (w[p] > options.min_weight) row.push_back({p, w[p]});
      if (row.empty()) {  // a vertex among many parts, each at most min_weight: its largest
        int largest = 0;
        w.maxCoeff(&largest);
        row.push_back({largest, 1.0});
      }
      normalize_influences(row);
      out.vertex_influences.insert(out.vertex_influences.end(), row.begin(), row.end());
    }
    out.vertex_influence_offsets.push_back(static_cast<int>(out.vertex_influences.size()));
  }
  weights = std::move(out);
  return n;
}

}  // namespace skinstream
