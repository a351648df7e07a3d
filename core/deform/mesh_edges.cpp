#include "core/deform/mesh_edges.h"

#include <algorithm>

namespace skinstream {

std::vector<std::pair<int, int>> unique_edges(std::span<const std::array<int, 3>> triangles) {
  std::vector<std::pair<int, int>> edges;
  edges.reserve(triangles.size() * 3);
  for (const auto& t : triangles)
    for (int k = 0; k < 3; ++k) {
      const int a = t[k], b = t[(k + 1) % 3];
      if (a != b) edges.emplace_back(std::min(a, b), std::max(a, b));
    }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  return edges;
}

}  // namespace skinstream
