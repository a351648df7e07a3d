#include "core/baselines/linear_interpolation_fill.h"
#include "support/capture_gaps.h"

#include <gtest/gtest.h>

#include <stdexcept>

namespace skinstream {
namespace {

// Channel 0 moves on a straight line at constant speed; channel 1 on another.
Capture straight_lines(int frames) {
  Capture capture({"LKNE", "RKNE"}, frames, 120.0);
  for (int f = 0; f < frames; ++f) {
    capture.at(f, 0) = Vec3(10.0, -20.0, 900.0) + f * Vec3(1.5, 0.25, -3.0);
    capture.at(f, 1) = Vec3(-300.0, 40.0, 500.0) + f * Vec3(-0.5, 2.0, 0.125);
  }
  return capture;
}

using test::knock_out;

TEST(LinearFill, RejectsPositionsThatDoNotMatchLabelsAndFrames) {
  Capture capture = straight_lines(10);
  capture.positions.pop_back();
  EXPECT_THROW(fill_linear(capture), std::invalid_argument);
}

TEST(LinearFill, EmptyCaptureStaysEmpty) {
  const Capture filled = fill_linear(Capture({"LKNE"}, 0, 120.0));
  EXPECT_EQ(filled.frame_count, 0);
  EXPECT_TRUE(filled.positions.empty());
}

TEST(LinearFill, ExactOnALinearTrajectory) {
  const Capture truth = straight_lines(100);
  Capture holed = truth;
  knock_out(holed, 0, 5, 30);
  knock_out(holed, 0, 37, 1);  // gaps two frames apart share the sample between them
  knock_out(holed, 1, 50, 49);
  const Capture filled = fill_linear(holed);
  for (int f = 0; f < truth.frame_count; ++f)
    for (int p = 0; p < 2; ++p) {
      ASSERT_TRUE(filled.present(f, p)) << f << " " << p;
      EXPECT_NEAR((filled.at(f, p) - truth.at(f, p)).norm(), 0.0, 1e-9) << f << " " << p;
    }
}

TEST(LinearFill, InterpolatesBetweenTheBracketingSamples) {
  Capture capture({"LELB"}, 5, 100.0);
  capture.at(0, 0) = Vec3(0, 0, 0);
  capture.at(4, 0) = Vec3(8, -4, 12);
  const Capture filled = fill_linear(capture);
  EXPECT_TRUE(filled.at(1, 0).isApprox(Vec3(2, -1, 3)));
  EXPECT_TRUE(filled.at(2, 0).isApprox(Vec3(4, -2, 6)));
  EXPECT_TRUE(filled.at(3, 0).isApprox(Vec3(6, -3, 9)));
}

TEST(LinearFill, HoldsTheNearestSampleAtTheEnds) {
  Capture capture = straight_lines(20);
  knock_out(capture, 0, 0, 4);
  knock_out(capture, 0, 15, 5);
  const Capture filled = fill_linear(capture);
  for (int f = 0; f < 4; ++f) EXPECT_EQ(filled.at(f, 0), capture.at(4, 0));
  for (int f = 15; f < 20; ++f) EXPECT_EQ(filled.at(f, 0), capture.at(14, 0));
}

TEST(LinearFill, KeepsPresentSamplesAndNeverPresentChannelsAndUnlabelledChannels) {
  Capture capture({"LKNE", "RKNE", "*3"}, 12, 120.0);
  for (int f = 0; f < 12; ++f) {
    capture.at(f, 0) = Vec3(f, 2.0 * f, 3.0);
    if (f % 3 == 0) capture.at(f, 2) = Vec3(1, 1, 1);  // unlabelled fragments stay fragments
  }
  knock_out(capture, 0, 6, 2);
  const Capture filled = fill_linear(capture);
  for (int f = 0; f < 12; ++f) {
    if (f < 6 || f > 7) {
      EXPECT_EQ(filled.at(f, 0), capture.at(f, 0));
    }
    EXPECT_FALSE(filled.present(f, 1));
    EXPECT_EQ(filled.present(f, 2), f % 3 == 0);
  }
}

TEST(LinearFill, ASingleSampleIsHeldEverywhere) {
  Capture capture({"LKNE"}, 6, 120.0);
  capture.at(3, 0) = Vec3(7, 8, 9);
  const Capture filled = fill_linear(capture);
  for (int f = 0; f < 6; ++f) EXPECT_EQ(filled.at(f, 0), Vec3(7, 8, 9));
}

}  // namespace
}  // namespace skinstream
