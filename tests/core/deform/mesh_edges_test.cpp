#include "core/deform/mesh_edges.h"

#include <gtest/gtest.h>

namespace skinstream {
namespace {

// Two triangles sharing an edge, given in both windings, and a degenerate face: each edge once,
// smaller index first, sorted; the degenerate face adds only its one real edge.
TEST(MeshEdges, EachEdgeOnceSmallerIndexFirstSorted) {
  const std::vector<std::array<int, 3>> faces = {{0, 1, 2}, {2, 1, 3}, {4, 4, 3}};
  const std::vector<std::pair<int, int>> expected = {{0, 1}, {0, 2}, {1, 2}, {1, 3}, {2, 3}, {3, 4}};
  EXPECT_EQ(unique_edges(faces), expected);
  EXPECT_TRUE(unique_edges({}).empty());
}

}  // namespace
}  // namespace skinstream
