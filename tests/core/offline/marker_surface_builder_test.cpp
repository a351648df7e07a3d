#include "core/offline/marker_surface_builder.h"

#include <gtest/gtest.h>

#include "core/offline/marker_distance_stats.h"
#include "support/synthetic_limb.h"

namespace skinstream {
namespace {

std::vector<int> all_channels(const Capture& c) {
  std::vector<int> v(c.point_count());
  for (int p = 0; p < c.point_count(); ++p) v[p] = p;
  return v;
}

TEST(MarkerSurfaceBuilder, IsolatedMarkerStillGetsThreeNeighbours) {
  // Four markers on a line: no triangle is possible (slivers), yet each needs 3 neighbours.
  std::vector<Vec3> x = {Vec3(0, 0, 0), Vec3(40, 0, 0), Vec3(80, 0, 0), Vec3(120, 0, 0)};
  Eigen::MatrixXd d(4, 4);
  for (int a = 0; a < 4; ++a)
    for (int b = 0; b < 4; ++b) d(a, b) = (x[a] - x[b]).norm();
  const MarkerSurface s = build_marker_surface(x, d);
  EXPECT_TRUE(s.triangles.empty());
  EXPECT_EQ(s.markers_given_extra_neighbours, 4);
  for (const auto& ring : s.rings) EXPECT_EQ(ring.size(), 3u);
  for (const Vec3& n : s.normals) EXPECT_NEAR(n.norm(), 1.0, 1e-9);
}

TEST(MarkerSurfaceBuilder, CylinderGridIsAManifoldWithOutwardNormals) {
  const Capture limb = test::make_limb_capture();
  const std::vector<int> channels = all_channels(limb);
  const Eigen::MatrixXd skin = compute_marker_distance_stats(limb, channels).skin_distance();
  std::vector<Vec3> ref;
  for (int p : channels) ref.push_back(limb.at(0, p));
  const MarkerSurface s = build_marker_surface(ref, skin);
  EXPECT_GT(s.triangles.size(), 60u);
  EXPECT_EQ(s.markers_given_extra_neighbours, 0);
  // Every edge in at most two triangles.
  std::map<std::pair<int, int>, int> uses;
  for (const auto& t : s.triangles)
    for (int e = 0; e < 3; ++e) ++uses[{std::min(t[e], t[(e + 1) % 3]), std::max(t[e], t[(e + 1) % 3])}];
  for (const auto& [edge, count] : uses) EXPECT_LE(count, 2);
  // Normals point away from the cylinder's axis (the axis is the mean of each ring of markers).
  test::LimbOptions o;
  for (int l = 1; l + 1 < o.along; ++l) {
    Vec3 axis = Vec3::Zero();
    for (int a = 0; a < o.around; ++a) axis += ref[l * o.around + a] / o.around;
    for (int a = 0; a < o.around; ++a) EXPECT_GT(s.normals[l * o.around + a].dot(ref[l * o.around + a] - axis), 0.0);
  }
}

TEST(MarkerSurfaceBuilder, NeverJoinsPartsThatSlideAgainstEachOther) {
  // Two patches touching in the reference frame (a hand at a hip) but moving apart later:
  // skin distance keeps them apart even though they are nearest in the reference pose.
  test::LimbOptions o;
  o.frames = 240;
  const Capture a = test::make_limb_capture(o);
  std::vector<std::string> labels = a.labels;
  for (auto& l : a.labels) labels.push_back("other_" + l);
  Capture both(labels, o.frames, o.rate);
  const int n = a.point_count();
  for (int f = 0; f < o.frames; ++f)
    for (int p = 0; p < n; ++p) {
      both.at(f, p) = a.at(f, p);
      // The second limb sits 130 mm beside the first at frame 0 and drifts up to 600 mm away.
      both.at(f, n + p) = a.at(f, p) + Vec3(130.0 + 470.0 * std::sin(M_PI * f / o.frames), 0, 0);
    }
  std::vector<int> channels(2 * n);
  for (int p = 0; p < 2 * n; ++p) channels[p] = p;
  const Eigen::MatrixXd skin = compute_marker_distance_stats(both, channels).skin_distance();
  std::vector<Vec3> ref;
  for (int p : channels) ref.push_back(both.at(0, p));
  const MarkerSurface s = build_marker_surface(ref, skin);
  for (const auto& t : s.triangles) {
    const bool first = t[0] < n;
    EXPECT_EQ(t[1] < n, first);
    EXPECT_EQ(t[2] < n, first);
  }
  for (int i = 0; i < 2 * n; ++i)
    for (int j : s.rings[i]) EXPECT_EQ(i < n, j < n) << "marker " << i << " joined to " << j;
}

}  // namespace
}  // namespace skinstream
