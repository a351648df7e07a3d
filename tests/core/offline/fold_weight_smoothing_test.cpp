#include "core/offline/fold_weight_smoothing.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace skinstream {
namespace {

// A strip of skin across a fold: kColumns columns of two vertices 10 mm apart, quads split
// along one diagonal. The first column follows part 0 (one side of the fold), the last part 1 (the other
// side); the vertices between carry part 2, a small leftover part bridging the fold, and the
// ones in kFold are the fold's (in_fold).
constexpr int kColumns = 9;
constexpr int kParts = 3;
int vertex(int column, int row) { return 2 * column + row; }

struct Strip {
  std::vector<Vec3> vertices;
  std::vector<std::array<int, 3>> faces;
  VertexPartWeights weights;
  Strip(int fold_first, int fold_last, double spacing = 10.0) {
    for (int c = 0; c + 1 < kColumns; ++c) {
      faces.push_back({vertex(c, 0), vertex(c + 1, 0), vertex(c + 1, 1)});
      faces.push_back({vertex(c, 0), vertex(c + 1, 1), vertex(c, 1)});
    }
    for (int c = 0; c < kColumns; ++c)
      for (int r = 0; r < 2; ++r) {
        vertices.emplace_back(spacing * c, spacing * r, 0.0);
        const int part = c == 0 ? 0 : (c == kColumns - 1 ? 1 : 2);
        weights.vertex_influences.push_back({part, 1.0});
        weights.vertex_influence_offsets.push_back(static_cast<int>(weights.vertex_influences.size()));
        weights.in_fold.push_back(c >= fold_first && c <= fold_last);
      }
  }
  int vertex_count() const { return 2 * kColumns; }
};

// Each vertex's weights as a dense row.
std::vector<std::array<double, kParts>> dense(const VertexPartWeights& w) {
  std::vector<std::array<double, kParts>> out(w.vertex_influence_offsets.size() - 1, std::array<double, kParts>{});
  for (size_t v = 0; v + 1 < w.vertex_influence_offsets.size(); ++v)
    for (int k = w.vertex_influence_offsets[v]; k < w.vertex_influence_offsets[v + 1]; ++k)
      out[v][w.vertex_influences[k].part] = w.vertex_influences[k].weight;
  return out;
}

std::vector<std::vector<int>> mesh_neighbours(const std::vector<std::array<int, 3>>& faces, int vertex_count) {
  std::vector<std::vector<int>> out(vertex_count);
  for (const auto& f : faces)
    for (int c = 0; c < 3; ++c) {
      const int a = f[c], b = f[(c + 1) % 3];
      if (std::find(out[a].begin(), out[a].end(), b) == out[a].end()) out[a].push_back(b);
      if (std::find(out[b].begin(), out[b].end(), a) == out[b].end()) out[b].push_back(a);
    }
  return out;
}

TEST(FoldWeightSmoothing, InsideTheFoldEachVertexIsTheMeanOfItsMeshNeighbours) {
  Strip strip(1, kColumns - 2);  // every column between the two sides
  FoldSmoothingOptions options;  // band_mm 0: the fold's vertices alone
  options.min_weight = 0.0;
  EXPECT_EQ(smooth_fold_weights(strip.vertices, strip.faces, {}, kParts, strip.weights, options), 2 * (kColumns - 2));
  const auto w = dense(strip.weights);
  const auto neighbours = mesh_neighbours(strip.faces, strip.vertex_count());
  for (int c = 1; c + 1 < kColumns; ++c)
    for (int r = 0; r < 2; ++r) {
      const int v = vertex(c, r);
      for (int p = 0; p < kParts; ++p) {
        double mean = 0.0;
        for (int u : neighbours[v]) mean += w[u][p] / static_cast<double>(neighbours[v].size());
        EXPECT_NEAR(w[v][p], mean, 1e-5) << "vertex " << v << " part " << p;
      }
      // The leftover part bridging the fold is gone: the skin follows the two sides.
      EXPECT_LT(w[v][2], 1e-5);
      EXPECT_NEAR(w[v][0] + w[v][1] + w[v][2], 1.0, 1e-12);
    }
  // From one side to the other: part 1's share grows column by column.
  for (int c = 1; c + 1 < kColumns; ++c) EXPECT_GT(w[vertex(c, 0)][1], w[vertex(c - 1, 0)][1]) << c;
  // The sides keep their weights exactly.
  EXPECT_EQ(w[vertex(0, 0)][0], 1.0);
  EXPECT_EQ(w[vertex(kColumns - 1, 1)][1], 1.0);
}

TEST(FoldWeightSmoothing, SmallSharesAreDroppedAndTheRestRenormalised) {
  Strip strip(1, kColumns - 2);
  FoldSmoothingOptions options;  // min_weight 0.02, the default
  smooth_fold_weights(strip.vertices, strip.faces, {}, kParts, strip.weights, options);
  for (int v = 0; v < strip.vertex_count(); ++v) {
    double sum = 0.0;
    for (int k = strip.weights.vertex_influence_offsets[v]; k < strip.weights.vertex_influence_offsets[v + 1]; ++k) {
      EXPECT_GT(strip.weights.vertex_influences[k].weight, 0.02) << v;
      EXPECT_NE(strip.weights.vertex_influences[k].part, 2) << v;  // the leftover part's 1e-6 trace
      sum += strip.weights.vertex_influences[k].weight;
    }
    EXPECT_NEAR(sum, 1.0, 1e-12) << v;
  }
}

TEST(FoldWeightSmoothing, ABandAroundTheFoldAlsoHoldsItsOwnWeights) {
  Strip strip(3, 5);  // the fold: columns 3-5; a band of 10 mm: columns 2 and 6
  const auto before = dense(strip.weights);
  FoldSmoothingOptions options;
  options.band_mm = 10.0;
  options.band_pull = 1.0;
  options.min_weight = 0.0;
  EXPECT_EQ(smooth_fold_weights(strip.vertices, strip.faces, {}, kParts, strip.weights, options), 2 * 5);
  const auto w = dense(strip.weights);
  const auto neighbours = mesh_neighbours(strip.faces, strip.vertex_count());
  for (int c : {2, 6})
    for (int r = 0; r < 2; ++r) {
      const int v = vertex(c, r);
      for (int p = 0; p < kParts; ++p) {
        double sum = 0.0;
        for (int u : neighbours[v]) sum += w[u][p];
        // (neighbours + pull) w = the sum of the neighbours' weights + pull * its own
        EXPECT_NEAR((neighbours[v].size() + 1.0) * w[v][p], sum + before[v][p], 1e-5) << "vertex " << v << " part " << p;
      }
    }
  // Beyond the band nothing moves; columns 1 and 7 still carry the leftover part alone.
  for (int c : {0, 1, 7, 8})
    for (int r = 0; r < 2; ++r) EXPECT_EQ(w[vertex(c, r)], before[vertex(c, r)]) << c;
}

// The band is a distance along the mesh, so a finer mesh smooths the same stretch of skin: 10 mm
// is one column either side of the fold here, two on a strip twice as fine.
TEST(FoldWeightSmoothing, TheBandIsADistanceNotAMeshRing) {
  FoldSmoothingOptions options;
  options.band_mm = 10.0;
  Strip coarse(3, 5), fine(3, 5, 5.0);
  EXPECT_EQ(smooth_fold_weights(coarse.vertices, coarse.faces, {}, kParts, coarse.weights, options), 2 * (3 + 2));
  EXPECT_EQ(smooth_fold_weights(fine.vertices, fine.faces, {}, kParts, fine.weights, options), 2 * (3 + 4));
  // A vertex under a marker neither joins the band nor carries it on.
  Strip blocked(3, 5, 5.0);
  std::vector<char> under(blocked.vertex_count(), 0);
  under[vertex(2, 0)] = under[vertex(2, 1)] = 1;
  EXPECT_EQ(smooth_fold_weights(blocked.vertices, blocked.faces, under, kParts, blocked.weights, options), 2 * (3 + 2));
}

TEST(FoldWeightSmoothing, VerticesUnderAMarkerAndOutsideFoldsKeepTheirWeights) {
  Strip strip(1, kColumns - 2);
  std::vector<char> under(strip.vertex_count(), 0);
  under[vertex(4, 0)] = 1;
  const auto before = dense(strip.weights);
  const FoldSmoothingOptions options;  // the fold's vertices alone
  EXPECT_EQ(smooth_fold_weights(strip.vertices, strip.faces, under, kParts, strip.weights, options), 2 * (kColumns - 2) - 1);
  EXPECT_EQ(dense(strip.weights)[vertex(4, 0)], before[vertex(4, 0)]);

  Strip no_fold(1, 0);  // no column is in the fold
  const VertexPartWeights unchanged = no_fold.weights;
  EXPECT_EQ(smooth_fold_weights(no_fold.vertices, no_fold.faces, {}, kParts, no_fold.weights), 0);
  EXPECT_EQ(dense(no_fold.weights), dense(unchanged));
  EXPECT_EQ(no_fold.weights.vertex_influence_offsets, unchanged.vertex_influence_offsets);
}

TEST(FoldWeightSmoothing, RejectsBadInputs) {
  const Strip strip(1, kColumns - 2);
  auto run = [&](auto change) {
    Strip copy = strip;
    std::vector<char> under;
    int parts = kParts;
    FoldSmoothingOptions options;
    change(copy, under, parts, options);
    return smooth_fold_weights(copy.vertices, copy.faces, under, parts, copy.weights, options);
  };
  EXPECT_THROW(run([](Strip& s, auto&, int&, auto&) { s.weights.in_fold.pop_back(); }), std::invalid_argument);
  EXPECT_THROW(run([](Strip&, std::vector<char>& under, int&, auto&) { under.assign(3, 0); }), std::invalid_argument);
  EXPECT_THROW(run([](Strip& s, auto&, int&, auto&) { s.faces[0][1] = 2 * kColumns; }), std::invalid_argument);
  EXPECT_THROW(run([](Strip& s, auto&, int&, auto&) { s.weights.vertex_influence_offsets.back() += 1; }),
               std::invalid_argument);
  EXPECT_THROW(run([](Strip&, auto&, int& parts, auto&) { parts = 2; }), std::invalid_argument);  // part 2 named
  EXPECT_THROW(run([](Strip& s, auto&, int&, auto&) { s.vertices.pop_back(); }), std::invalid_argument);
  EXPECT_THROW(run([](Strip& s, auto&, int&, auto&) { s.vertices[3].x() = std::nan(""); }), std::invalid_argument);
  EXPECT_THROW(run([](Strip&, auto&, int&, FoldSmoothingOptions& o) { o.band_mm = -1.0; }), std::invalid_argument);
  EXPECT_THROW(run([](Strip&, auto&, int&, FoldSmoothingOptions& o) { o.band_pull = -1.0; }), std::invalid_argument);
  EXPECT_THROW(run([](Strip&, auto&, int&, FoldSmoothingOptions& o) { o.min_weight = 1.0; }), std::invalid_argument);
}

}  // namespace
}  // namespace skinstream
