#pragma once
// The edges of a triangle mesh, each once: (a, b) with a < b, sorted. Degenerate edges (a face
// naming one vertex twice) are left out. Registration's smoothness term and the fold smoothing's
// graph over the detailed mesh both run on these, and the strain of a body (surface_strain.h).
#include <array>
#include <span>
#include <utility>
#include <vector>

namespace skinstream {

std::vector<std::pair<int, int>> unique_edges(std::span<const std::array<int, 3>> triangles);

}  // namespace skinstream
