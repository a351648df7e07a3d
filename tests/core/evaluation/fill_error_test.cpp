#include "core/evaluation/fill_error.h"

#include <gtest/gtest.h>

#include <stdexcept>

namespace skinstream {
namespace {

// Truth at the origin; the filled copy is off by a chosen distance along x.
struct Pair {
  Capture truth, filled;
};

Pair make_pair(const std::vector<std::string>& labels, int frames) {
  Pair pair{Capture(labels, frames, 120.0), Capture(labels, frames, 120.0)};
  for (Vec3& p : pair.truth.positions) p = Vec3(10, 20, 30);
  pair.filled = pair.truth;
  return pair;
}

TEST(FillError, RejectsMismatchedCaptures) {
  const Pair a = make_pair({"LELB"}, 10);
  const Pair b = make_pair({"LELB", "RELB"}, 10);
  const Pair c = make_pair({"LELB"}, 11);
  EXPECT_THROW(fill_error(a.truth, b.filled, {}, {1.0}), std::invalid_argument);
  EXPECT_THROW(fill_error(a.truth, c.filled, {}, {1.0}), std::invalid_argument);
  Capture broken = a.filled;
  broken.positions.pop_back();
  EXPECT_THROW(fill_error(a.truth, broken, {}, {1.0}), std::invalid_argument);
}

TEST(FillError, RejectsBadNormalisersAndGaps) {
  const Pair a = make_pair({"LELB", "RELB"}, 10);
  EXPECT_THROW(fill_error(a.truth, a.filled, {}, {1.0}), std::invalid_argument);
  EXPECT_THROW(fill_error(a.truth, a.filled, {{1, 2, 3}}, {1.0, 0.0}), std::invalid_argument);
  EXPECT_THROW(fill_error(a.truth, a.filled, {{1, 2, 3}}, {1.0, -2.0}), std::invalid_argument);
  EXPECT_THROW(fill_error(a.truth, a.filled, {{1, 2, 3}}, {1.0, NAN}), std::invalid_argument);
  EXPECT_NO_THROW(fill_error(a.truth, a.filled, {{0, 2, 3}}, {1.0, 0.0}));  // no gap on channel 1
  EXPECT_THROW(fill_error(a.truth, a.filled, {{2, 2, 3}}, {1.0, 1.0}), std::invalid_argument);
  EXPECT_THROW(fill_error(a.truth, a.filled, {{0, 8, 3}}, {1.0, 1.0}), std::invalid_argument);
  EXPECT_THROW(fill_error(a.truth, a.filled, {{0, -1, 3}}, {1.0, 1.0}), std::invalid_argument);
}

TEST(FillError, StatisticsOnHandMadeErrors) {
  Pair pair = make_pair({"Male:LELB", "RKNE"}, 10);
  // LELB: errors 1..5 mm at frames 2..6; normaliser 2 mm.
  for (int k = 0; k < 5; ++k) pair.filled.at(2 + k, 0) += Vec3(0, 0, k + 1.0);
  // RKNE: errors 3-4-5 triangles: 5 mm at frames 0..1; normaliser 10 mm.
  pair.filled.at(0, 1) += Vec3(3, 4, 0);
  pair.filled.at(1, 1) += Vec3(0, 3, 4);
  // An error outside any gap is not counted.
  pair.filled.at(9, 0) += Vec3(100, 0, 0);
  const FillErrorReport report = fill_error(pair.truth, pair.filled, {{0, 2, 5}, {1, 0, 2}}, {2.0, 10.0});

  // All: {1, 2, 3, 4, 5, 5, 5}
  EXPECT_EQ(report.millimetres.count, 7);
  EXPECT_NEAR(report.millimetres.mean, 25.0 / 7.0, 1e-12);
  EXPECT_NEAR(report.millimetres.median, 4.0, 1e-12);
  EXPECT_NEAR(report.millimetres.p95, 5.0, 1e-12);
  EXPECT_NEAR(report.millimetres.max, 5.0, 1e-12);
  // Normalised: {0.5, 1, 1.5, 2, 2.5, 0.5, 0.5}
  EXPECT_NEAR(report.normalised.mean, 8.5 / 7.0, 1e-12);
  EXPECT_NEAR(report.normalised.median, 1.0, 1e-12);
  EXPECT_NEAR(report.normalised.max, 2.5, 1e-12);

  ASSERT_EQ(report.regions.size(), 2u);  // head-to-toe order: elbow before knee
  EXPECT_EQ(report.regions[0].region, "elbow");
  EXPECT_EQ(report.regions[0].millimetres.count, 5);
  EXPECT_NEAR(report.regions[0].millimetres.mean, 3.0, 1e-12);
  EXPECT_NEAR(report.regions[0].normalised.p95, 2.5, 1e-12);
  EXPECT_EQ(report.regions[1].region, "knee");
  EXPECT_NEAR(report.regions[1].millimetres.median, 5.0, 1e-12);
  EXPECT_NEAR(report.regions[1].normalised.mean, 0.5, 1e-12);
  EXPECT_EQ(report.unfilled, 0);
  EXPECT_EQ(report.truth_missing, 0);
}

TEST(FillError, CountsUnfilledAndUnverifiableSamplesApart) {
  Pair pair = make_pair({"LTHI"}, 10);
  pair.filled.at(3, 0) = missing_point();
  pair.filled.at(4, 0) += Vec3(2, 0, 0);
  pair.truth.at(5, 0) = missing_point();
  const FillErrorReport report = fill_error(pair.truth, pair.filled, {{0, 3, 3}}, {1.0});
  EXPECT_EQ(report.unfilled, 1);
  EXPECT_EQ(report.truth_missing, 1);
  EXPECT_EQ(report.millimetres.count, 1);
  EXPECT_EQ(report.millimetres.max, 2.0);
}

TEST(FillError, NoGapsGiveAnEmptyReport) {
  const Pair pair = make_pair({"LTHI"}, 10);
  const FillErrorReport report = fill_error(pair.truth, pair.filled, {}, {1.0});
  EXPECT_EQ(report.millimetres.count, 0);
  EXPECT_TRUE(report.regions.empty());
}

TEST(FillError, UnknownMarkersGoToOther) {
  Pair pair = make_pair({"mystery", "*4"}, 4);
  const FillErrorReport report = fill_error(pair.truth, pair.filled, {{0, 0, 2}, {1, 0, 1}}, {1.0, 1.0});
  ASSERT_EQ(report.regions.size(), 1u);
  EXPECT_EQ(report.regions[0].region, "other");
  EXPECT_EQ(report.regions[0].millimetres.count, 3);
}

}  // namespace
}  // namespace skinstream
