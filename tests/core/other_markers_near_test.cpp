#include "core/other_markers_near.h"

#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <vector>

namespace skinstream {
namespace {

using S = MarkerStatus;

// The filler's expectations from a table, counting what it was asked.
struct TableExpectation final : MarkerExpectation {
  explicit TableExpectation(int markers) : position(markers) {}
  std::vector<std::optional<Vec3>> position;
  int asked = 0;
  bool expected(int marker, Vec3& out, double* out_variance) override {
    ++asked;
    if (!position[marker]) return false;
    out = *position[marker];
    if (out_variance) *out_variance = 1.0;
    return true;
  }
};

// Five markers, all missing this frame, eps1 of 50 mm; each measured at x = 100 j in the last
// two frames, standing still.
struct NearFixture {
  static constexpr int kMarkers = 5;
  MarkerTracks tracks{kMarkers};
  std::vector<Vec3> points = std::vector<Vec3>(kMarkers, Vec3::Zero());
  std::vector<char> observed = std::vector<char>(kMarkers, 0);
  std::vector<int> missing = {0, 1, 2, 3, 4};
  std::vector<char> estimated = std::vector<char>(kMarkers, 0);
  std::vector<Vec3> estimate = std::vector<Vec3>(kMarkers, Vec3::Zero());
  std::vector<double> eps1 = std::vector<double>(kMarkers, 50.0);
  TableExpectation expectation{kMarkers};

  NearFixture() {
    std::vector<Vec3> last;
    for (int j = 0; j < kMarkers; ++j) last.push_back(Vec3(100.0 * j, 0, 0));
    const std::vector<S> measured(kMarkers, S::Measured);
    tracks.advance(last, measured);
    tracks.advance(last, measured);
  }
  FrameEstimates frame() const { return {points, observed, missing, estimated, estimate, eps1, tracks}; }
  void expect(int j, const Vec3& at) {
    estimated[j] = 1;
    estimate[j] = at;
    expectation.position[j] = at;
  }
};

TEST(OtherMarkersNear, TheNearestOtherExpectedMarkerWithinItsEps1) {
  NearFixture fx;
  const Vec3 p(0, 0, 0);
  fx.expect(1, Vec3(30, 0, 0));
  fx.expect(2, Vec3(0, 20, 0));
  fx.expect(3, Vec3(0, 0, 60));  // beyond eps1
  EXPECT_DOUBLE_EQ(nearest_other_expected(fx.frame(), fx.expectation, 0, p), 20.0);
  // Not the marker asked about, nor one measured this frame.
  EXPECT_DOUBLE_EQ(nearest_other_expected(fx.frame(), fx.expectation, 2, p), 30.0);
  fx.observed[1] = 1;
  EXPECT_TRUE(std::isinf(nearest_other_expected(fx.frame(), fx.expectation, 2, p)));
}

TEST(OtherMarkersNear, MarkersWhoseEq2EstimateIsFarAreNotAskedForTheirExpectation) {
  NearFixture fx;
  fx.expect(1, Vec3(151, 0, 0));                // eq. 2 estimate beyond three eps1
  fx.expectation.position[1] = Vec3(10, 0, 0);  // its fused expectation would have been near
  fx.expect(2, Vec3(149, 0, 0));
  fx.expectation.position[2] = Vec3(0, 10, 0);
  EXPECT_DOUBLE_EQ(nearest_other_expected(fx.frame(), fx.expectation, 0, Vec3::Zero()), 10.0);
  EXPECT_EQ(fx.expectation.asked, 1);
}

TEST(OtherMarkersNear, TracksStandInOnlyForMarkersWithNoExpectation) {
  NearFixture fx;
  const Vec3 p(100, 30, 0);  // 30 mm from where marker 1 stands still, 104 from marker 0
  EXPECT_DOUBLE_EQ(nearest_other_on_track(fx.frame(), fx.expectation, 0, p), 30.0);
  EXPECT_TRUE(std::isinf(nearest_other_on_track(fx.frame(), fx.expectation, 1, p)));  // its own
  fx.expectation.position[1] = Vec3(500, 0, 0);  // an estimate of its own: its track says nothing
  EXPECT_TRUE(std::isinf(nearest_other_on_track(fx.frame(), fx.expectation, 0, p)));
  fx.expectation.position[1].reset();
  std::vector<S> statuses(NearFixture::kMarkers, S::Measured);
  statuses[1] = S::Held;  // no position of its own last frame
  std::vector<Vec3> last;
  for (int j = 0; j < NearFixture::kMarkers; ++j) last.push_back(Vec3(100.0 * j, 0, 0));
  fx.tracks.advance(last, statuses);
  EXPECT_TRUE(std::isinf(nearest_other_on_track(fx.frame(), fx.expectation, 0, p)));
}

}  // namespace
}  // namespace skinstream
