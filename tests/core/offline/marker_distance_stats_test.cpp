#include "core/offline/marker_distance_stats.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

namespace skinstream {
namespace {

TEST(NearestMarkerDistances, AreEachMarkersNearestOther) {
  const std::vector<Vec3> markers{Vec3(0, 0, 0), Vec3(30, 0, 0), Vec3(30, 40, 0)};
  EXPECT_EQ(nearest_marker_distances(markers), (std::vector<double>{30.0, 30.0, 40.0}));
  const std::vector<double> alone = nearest_marker_distances(std::vector<Vec3>{Vec3::Zero()});
  ASSERT_EQ(alone.size(), 1u);
  EXPECT_TRUE(std::isinf(alone[0]));
}

TEST(MedianNearestMarkerDistance, IsTheTypicalSpacing) {
  // A 4 x 3 grid 40 mm apart, and one marker 10 mm from a corner: that pair is nearest at 10,
  // the other ten markers at 40.
  std::vector<Vec3> markers;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 3; ++j) markers.emplace_back(40.0 * i, 40.0 * j, 0.0);
  markers.emplace_back(-10.0, 0.0, 0.0);
  EXPECT_DOUBLE_EQ(median_nearest_marker_distance(markers), 40.0);
  EXPECT_THROW(median_nearest_marker_distance(std::vector<Vec3>{Vec3::Zero()}), std::invalid_argument);
}

}  // namespace
}  // namespace skinstream
