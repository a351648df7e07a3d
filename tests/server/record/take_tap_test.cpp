// The stream's side of a recording: frames copied only while a take records, into slots made
// beforehand (nothing allocated on the io or pipeline thread), dropped and counted when the
// writer is a whole ring behind, never blocking.
#include "server/record/take_tap.h"

#include <gtest/gtest.h>

#include <vector>

#include "support/allocation_counter.h"

namespace skinstream::server {
namespace {

MarkerFrame received_frame(uint32_t number, int unlabelled) {
  MarkerFrame frame(2);
  frame.frame_number = number;
  frame.source_time_ns = 1000 * number;
  frame.source_rate_hz = 100.0;
  frame.labelled[0] = Vec3(number, 2, 3);
  for (int i = 0; i < unlabelled; ++i) frame.unlabelled[i] = Vec3(10 + i, 0, 0);
  frame.unlabelled_count = unlabelled;
  frame.unknown_labels = 1;
  return frame;
}

TEST(TakeTap, RecordsNothingWhileNoTakeRecords) {
  TakeTap tap("A", {"M1", "M2"}, 2, 4);
  tap.record_received(received_frame(1, 0));
  EXPECT_EQ(tap.received().front(), nullptr);
  EXPECT_EQ(tap.source_rate_hz(), 100.0);  // the rate is followed all the same, for the next take's files
}

TEST(TakeTap, CopiesTheMarkersThenTheUnlabelledSlotsAndCountsThoseBeyond) {
  TakeTap tap("A", {"M1", "M2"}, 2, 4);
  EXPECT_EQ(tap.received_labels(), (std::vector<std::string>{"M1", "M2", "*1", "*2"}));
  tap.set_take(7);
  tap.record_received(received_frame(5, 3));
  const RecordedFrame* frame = tap.received().front();
  ASSERT_NE(frame, nullptr);
  EXPECT_EQ(frame->take, 7u);
  EXPECT_EQ(frame->frame_number, 5u);
  EXPECT_EQ(frame->source_time_ns, 5000);
  EXPECT_EQ(frame->points[0], Vec3(5, 2, 3));
  EXPECT_FALSE(is_present(frame->points[1]));
  EXPECT_EQ(frame->points[2], Vec3(10, 0, 0));
  EXPECT_EQ(frame->points[3], Vec3(11, 0, 0));
  EXPECT_EQ(frame->unlabelled, 3);  // one more than the slots: counted, not kept
  EXPECT_EQ(frame->unknown_labels, 1);
}

TEST(TakeTap, AFullRingDropsTheFrameForTheTakeAndCountsIt) {
  TakeTap tap("A", {"M1", "M2"}, 0, 2);
  tap.set_take(1);
  for (uint32_t f = 1; f <= 3; ++f) tap.record_received(received_frame(f, 0));
  EXPECT_EQ(tap.received_dropped(), 1u);
  EXPECT_EQ(tap.received().front()->frame_number, 1u);
  tap.received().pop();
  EXPECT_EQ(tap.received().front()->frame_number, 2u);
  tap.received().pop();
  EXPECT_EQ(tap.received().front(), nullptr);
}

TEST(TakeTap, PublishedFramesKeepEachSamplesStatus) {
  TakeTap tap("A", {"M1", "M2"}, 0, 2);
  tap.set_take(3);
  const std::vector<Vec3> positions{Vec3(1, 2, 3), Vec3(4, 5, 6)};
  const std::vector<MarkerStatus> status{MarkerStatus::Measured, MarkerStatus::FilledPca};
  tap.on_filled({9, 90, 99, positions, status});
  const RecordedFrame* frame = tap.published().front();
  ASSERT_NE(frame, nullptr);
  EXPECT_EQ(frame->frame_number, 9u);
  EXPECT_EQ(frame->points[1], Vec3(4, 5, 6));
  EXPECT_EQ(frame->status[1], static_cast<uint8_t>(MarkerStatus::FilledPca));
}

TEST(TakeTap, RecordingAFrameAllocatesNothing) {
  TakeTap tap("A", {"M1", "M2"}, 4, 8);
  tap.set_take(1);
  const MarkerFrame frame = received_frame(1, 6);
  const std::vector<Vec3> positions{Vec3(1, 2, 3), Vec3(4, 5, 6)};
  const std::vector<MarkerStatus> status{MarkerStatus::Measured, MarkerStatus::Held};
  test::CountAllocations allocations;
  for (int i = 0; i < 20; ++i) {  // beyond the ring: the drops allocate nothing either
    tap.record_received(frame);
    tap.on_filled({1, 0, 0, positions, status});
  }
  EXPECT_EQ(allocations.count(), 0u);
  EXPECT_EQ(tap.received_dropped(), 12u);
}

}  // namespace
}  // namespace skinstream::server
