// Unlabelled points into a take's channels: a continuing trajectory keeps its channel, a new one
// (or one without an id) takes only a channel empty the frame before, so that read back, where a
// channel is a trajectory, the same fragments begin and end as they did live.
#include "server/record/unlabelled_slots.h"

#include <gtest/gtest.h>

#include <vector>

namespace skinstream::server {
namespace {

std::vector<int> assign(UnlabelledSlots& slots, std::vector<int> ids, int* kept = nullptr) {
  std::vector<int> out(ids.size());
  const int n = slots.assign(ids, out);
  if (kept) *kept = n;
  return out;
}

TEST(UnlabelledSlots, AContinuingTrajectoryKeepsItsChannelWhateverItsPlaceInTheFrame) {
  UnlabelledSlots slots(4);
  EXPECT_EQ(assign(slots, {10, 11}), (std::vector<int>{0, 1}));
  EXPECT_EQ(assign(slots, {11, 10}), (std::vector<int>{1, 0}));
}

TEST(UnlabelledSlots, ANewTrajectoryTakesOnlyAChannelThatRestedAFrame) {
  UnlabelledSlots slots(3);
  EXPECT_EQ(assign(slots, {10, 11}), (std::vector<int>{0, 1}));
  // 10 ends, 12 begins: not in channel 0, which 10 held the frame before (it would read as 10 going on).
  EXPECT_EQ(assign(slots, {11, 12}), (std::vector<int>{1, 2}));
  // Channel 0 rested a frame: free for the next new one.
  EXPECT_EQ(assign(slots, {11, 12, 13}), (std::vector<int>{1, 2, 0}));
}

TEST(UnlabelledSlots, PointsWithoutAnIdNeverContinueAChannel) {
  UnlabelledSlots slots(4);
  EXPECT_EQ(assign(slots, {-1, -1}), (std::vector<int>{0, 1}));
  EXPECT_EQ(assign(slots, {-1, -1}), (std::vector<int>{2, 3}));
  EXPECT_EQ(assign(slots, {-1, -1}), (std::vector<int>{0, 1}));
}

TEST(UnlabelledSlots, ATrajectoryBackAfterAGapReturnsToItsChannel) {
  UnlabelledSlots slots(4);
  assign(slots, {10, 11});
  assign(slots, {11});
  EXPECT_EQ(assign(slots, {10, 11}), (std::vector<int>{0, 1}));
}

TEST(UnlabelledSlots, PointsBeyondTheRestedChannelsAreNotKept) {
  UnlabelledSlots slots(2);
  int kept = 0;
  EXPECT_EQ(assign(slots, {1, 2, 3}, &kept), (std::vector<int>{0, 1, -1}));
  EXPECT_EQ(kept, 2);
  EXPECT_EQ(assign(slots, {4}, &kept), (std::vector<int>{-1}));  // both channels were in use
  EXPECT_EQ(kept, 0);
}

TEST(UnlabelledSlots, TheSameIdTwiceInAFrameGetsTwoChannels) {
  UnlabelledSlots slots(4);
  EXPECT_EQ(assign(slots, {7, 7}), (std::vector<int>{0, 1}));
}

}  // namespace
}  // namespace skinstream::server
