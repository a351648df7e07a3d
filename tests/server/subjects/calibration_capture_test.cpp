#include "server/subjects/calibration_capture.h"

#include <gtest/gtest.h>

#include <array>

#include "support/allocation_counter.h"

namespace skinstream::server {
namespace {

MarkerFrame frame_with(int markers, double x) {
  MarkerFrame frame(markers);
  for (int m = 0; m < markers; ++m) frame.labelled[static_cast<size_t>(m)] = Vec3(x, m, 0.0);
  return frame;
}

TEST(CalibrationCapture, KeepsTheFramesAsTheyCameUntilFullAndAllocatesNothingPerFrame) {
  CalibrationCapture capture({"A", "B", "C"}, 4, 120.0);
  std::vector<MarkerFrame> frames;
  for (int f = 0; f < 5; ++f) frames.push_back(frame_with(3, f));
  frames[1].labelled[2] = missing_point();
  std::array<bool, 5> full{};
  {
    test::CountAllocations allocations;
    for (size_t f = 0; f < frames.size(); ++f) full[f] = capture.add(frames[f]);
    EXPECT_EQ(allocations.count(), 0u);
  }
  EXPECT_EQ(full, (std::array<bool, 5>{false, false, false, true, true}));  // the fifth is not kept
  EXPECT_EQ(capture.frames(), 4);
  const Capture taken = capture.take();
  EXPECT_EQ(taken.labels, (std::vector<std::string>{"A", "B", "C"}));
  EXPECT_EQ(taken.frame_count, 4);
  EXPECT_DOUBLE_EQ(taken.rate_hz, 120.0);
  EXPECT_EQ(taken.at(3, 1), Vec3(3.0, 1.0, 0.0));
  EXPECT_FALSE(taken.present(1, 2));
  EXPECT_TRUE(taken.present(1, 1));
}

TEST(CalibrationCapture, TakenBeforeFullHoldsOnlyTheFramesRecorded) {
  CalibrationCapture capture({"A", "B"}, 10, 100.0);
  capture.add(frame_with(2, 1.0));
  capture.add(frame_with(2, 2.0));
  const Capture taken = capture.take();
  EXPECT_EQ(taken.frame_count, 2);
  EXPECT_EQ(taken.positions.size(), 4u);
  EXPECT_EQ(taken.at(1, 0), Vec3(2.0, 0.0, 0.0));
}

}  // namespace
}  // namespace skinstream::server
