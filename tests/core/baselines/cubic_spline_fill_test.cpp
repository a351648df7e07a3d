#include "core/baselines/cubic_spline_fill.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <stdexcept>

#include "core/baselines/linear_interpolation_fill.h"

namespace skinstream {
namespace {

Capture trajectory(int frames, const std::function<Vec3(double)>& at) {
  Capture capture({"LWRA"}, frames, 120.0);
  for (int f = 0; f < frames; ++f) capture.at(f, 0) = at(f);
  return capture;
}

void knock_out(Capture& capture, int first, int length) {
  for (int f = first; f < first + length; ++f) capture.at(f, 0) = missing_point();
}

double largest_error(const Capture& filled, const Capture& truth) {
  double worst = 0.0;
  for (int f = 0; f < truth.frame_count; ++f)
    worst = std::max(worst, (filled.at(f, 0) - truth.at(f, 0)).norm());
  return worst;
}

Vec3 cubic(double f) {
  const double t = f / 10.0;  // keeps values in the hundreds of mm
  return Vec3(3.0 + 2.0 * t - 1.5 * t * t + 0.25 * t * t * t, -40.0 + 0.5 * t * t * t,
              700.0 - 8.0 * t + t * t);
}

TEST(CubicSplineFill, RejectsAWindowBelowOne) {
  const Capture capture = trajectory(10, cubic);
  EXPECT_THROW(fill_cubic_spline(capture, {.window = 0}), std::invalid_argument);
}

TEST(CubicSplineFill, RejectsPositionsThatDoNotMatchLabelsAndFrames) {
  Capture capture = trajectory(10, cubic);
  capture.positions.push_back(Vec3::Zero());
  EXPECT_THROW(fill_cubic_spline(capture), std::invalid_argument);
}

TEST(CubicSplineFill, ExactOnACubicPolynomial) {
  const Capture truth = trajectory(120, cubic);
  Capture holed = truth;
  knock_out(holed, 20, 25);  // long gap
  knock_out(holed, 50, 3);   // a second gap inside the first one's window: uneven knots
  knock_out(holed, 56, 1);
  knock_out(holed, 100, 15);
  EXPECT_LT(largest_error(fill_cubic_spline(holed), truth), 1e-9);
}

TEST(CubicSplineFill, ExactOnACubicWithFewKnots) {
  // Two knots before the gap and two after: the not-a-knot spline is the cubic itself.
  const Capture truth = trajectory(12, cubic);
  Capture holed = truth;
  knock_out(holed, 2, 8);
  EXPECT_LT(largest_error(fill_cubic_spline(holed), truth), 1e-9);
}

TEST(CubicSplineFill, ThreeKnotsGiveTheParabolaAndTwoTheLine) {
  const auto parabola = [](double f) { return Vec3(f * f, 3.0 - f, 2.0 * f * f - f); };
  const Capture truth = trajectory(8, parabola);
  Capture holed = truth;
  knock_out(holed, 1, 5);  // knots 0, 6, 7
  EXPECT_LT(largest_error(fill_cubic_spline(holed), truth), 1e-9);

  Capture two({"LWRA"}, 5, 120.0);
  two.at(0, 0) = Vec3(0, 0, 0);
  two.at(4, 0) = Vec3(4, 8, -4);
  EXPECT_TRUE(fill_cubic_spline(two).at(1, 0).isApprox(Vec3(1, 2, -1)));
}

TEST(CubicSplineFill, NaturalEndsAreExactOnLinesButNotOnCubics) {
  const auto line = [](double f) { return Vec3(2.0 * f, -f, 5.0); };
  Capture holed_line = trajectory(60, line);
  knock_out(holed_line, 20, 10);
  EXPECT_LT(largest_error(fill_cubic_spline(holed_line, {.end = SplineEnd::natural}), trajectory(60, line)),
            1e-9);

  const Capture truth = trajectory(40, cubic);
  Capture holed = truth;
  knock_out(holed, 3, 20);  // knots near the ends: the natural end condition shows
  EXPECT_GT(largest_error(fill_cubic_spline(holed, {.end = SplineEnd::natural}), truth), 1e-3);
}

TEST(CubicSplineFill, BeatsLinearOnASine) {
  const auto sine = [](double f) {
    const double phase = 2.0 * M_PI * f / 120.0;  // 1 Hz at 120 Hz
    return Vec3(100.0 * std::sin(phase), 50.0 * std::cos(phase), 900.0);
  };
  const Capture truth = trajectory(480, sine);
  Capture holed = truth;
  knock_out(holed, 100, 30);
  knock_out(holed, 300, 12);
  const double spline_error = largest_error(fill_cubic_spline(holed), truth);
  const double linear_error = largest_error(fill_linear(holed), truth);
  EXPECT_LT(spline_error, 0.1 * linear_error) << spline_error << " vs " << linear_error;
}

TEST(CubicSplineFill, UsesOnlyTheWindowAroundEachGap) {
  const Capture truth = trajectory(200, cubic);
  Capture holed = truth;
  knock_out(holed, 100, 10);
  Capture disturbed = holed;
  disturbed.at(100 - 5, 0) += Vec3(0, 0, 50);   // inside a 10-knot window
  disturbed.at(100 - 11, 0) += Vec3(0, 0, 50);  // outside it
  Capture far_only = holed;
  far_only.at(100 - 11, 0) += Vec3(0, 0, 50);
  const CubicSplineOptions options{.window = 10};
  EXPECT_EQ(fill_cubic_spline(far_only, options).at(105, 0), fill_cubic_spline(holed, options).at(105, 0));
  EXPECT_NE(fill_cubic_spline(disturbed, options).at(105, 0), fill_cubic_spline(holed, options).at(105, 0));
}

TEST(CubicSplineFill, HoldsEndsAndLeavesNeverPresentChannelsMissing) {
  Capture capture({"LWRA", "RWRA"}, 30, 120.0);
  for (int f = 0; f < 30; ++f) capture.at(f, 0) = cubic(f);
  knock_out(capture, 0, 5);
  knock_out(capture, 26, 4);
  const Capture filled = fill_cubic_spline(capture);
  for (int f = 0; f < 5; ++f) EXPECT_EQ(filled.at(f, 0), capture.at(5, 0));
  for (int f = 26; f < 30; ++f) EXPECT_EQ(filled.at(f, 0), capture.at(25, 0));
  for (int f = 0; f < 30; ++f) EXPECT_FALSE(filled.present(f, 1));
}

}  // namespace
}  // namespace skinstream
