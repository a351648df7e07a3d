#include "server/pipeline/frame_mailbox.h"

#include <gtest/gtest.h>

#include "support/allocation_counter.h"

namespace skinstream::server {
namespace {

void post_frame(FrameMailbox& mailbox, uint32_t number, uint64_t generation = 1) {
  MarkerFrame& f = mailbox.writable();
  f.frame_number = number;
  f.labelled[0] = Vec3(number, 0, 0);
  mailbox.post(generation);
}

TEST(FrameMailbox, EmptyMailboxTimesOut) {
  FrameMailbox mailbox(3);
  uint64_t generation = 0;
  EXPECT_EQ(mailbox.take(std::chrono::milliseconds(1), generation), nullptr);
}

TEST(FrameMailbox, NewestFrameWinsAndOverwrittenFramesAreCounted) {
  FrameMailbox mailbox(3);
  post_frame(mailbox, 10);
  post_frame(mailbox, 11);
  post_frame(mailbox, 12, 2);
  uint64_t generation = 0;
  const MarkerFrame* f = mailbox.take(std::chrono::milliseconds(0), generation);
  ASSERT_NE(f, nullptr);
  EXPECT_EQ(f->frame_number, 12u);
  EXPECT_EQ(f->labelled[0].x(), 12.0);
  EXPECT_EQ(generation, 2u);
  EXPECT_EQ(mailbox.dropped(), 2u);
  EXPECT_EQ(mailbox.posted(), 3u);
  EXPECT_EQ(mailbox.take(std::chrono::milliseconds(0), generation), nullptr);  // taken once only
}

TEST(FrameMailbox, FrameTakenStaysIntactWhileTheWriterGoesOn) {
  FrameMailbox mailbox(3);
  post_frame(mailbox, 1);
  uint64_t generation = 0;
  const MarkerFrame* taken = mailbox.take(std::chrono::milliseconds(0), generation);
  for (uint32_t n = 2; n < 10; ++n) post_frame(mailbox, n);
  EXPECT_EQ(taken->frame_number, 1u);
  EXPECT_EQ(mailbox.take(std::chrono::milliseconds(0), generation)->frame_number, 9u);
  EXPECT_EQ(mailbox.dropped(), 7u);  // 2..8 overwritten
}

TEST(FrameMailbox, PostingAllocatesNothing) {
  FrameMailbox mailbox(350);
  test::CountAllocations allocations;
  for (uint32_t n = 0; n < 100; ++n) post_frame(mailbox, n);
  uint64_t generation = 0;
  mailbox.take(std::chrono::milliseconds(0), generation);
  EXPECT_EQ(allocations.count(), 0u);
}

TEST(FrameMailbox, CloseWakesTheReader) {
  FrameMailbox mailbox(3);
  mailbox.close();
  uint64_t generation = 0;
  EXPECT_EQ(mailbox.take(std::chrono::seconds(10), generation), nullptr);
}

}  // namespace
}  // namespace skinstream::server
