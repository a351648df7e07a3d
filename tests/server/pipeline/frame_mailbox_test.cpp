#include "server/pipeline/frame_mailbox.h"

#include <gtest/gtest.h>

#include <stdexcept>
#include <thread>
#include <vector>

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

std::vector<uint32_t> take_all(FrameMailbox& mailbox) {
  std::vector<uint32_t> numbers;
  uint64_t generation = 0;
  while (const MarkerFrame* f = mailbox.take(std::chrono::milliseconds(0), generation)) numbers.push_back(f->frame_number);
  return numbers;
}

TEST(FrameMailbox, FramesArrivingTogetherAreAllTakenInOrder) {
  FrameMailbox mailbox(3);  // the default backlog, 3
  post_frame(mailbox, 10);
  post_frame(mailbox, 11);
  post_frame(mailbox, 12, 2);
  EXPECT_EQ(mailbox.waiting(), 3);
  uint64_t generation = 0;
  const MarkerFrame* f = mailbox.take(std::chrono::milliseconds(0), generation);
  ASSERT_NE(f, nullptr);
  EXPECT_EQ(f->frame_number, 10u);
  EXPECT_EQ(f->labelled[0].x(), 10.0);
  EXPECT_EQ(generation, 1u);
  EXPECT_EQ(mailbox.take(std::chrono::milliseconds(0), generation)->frame_number, 11u);
  f = mailbox.take(std::chrono::milliseconds(0), generation);
  EXPECT_EQ(f->frame_number, 12u);
  EXPECT_EQ(generation, 2u);  // each frame keeps its own generation
  EXPECT_EQ(mailbox.dropped(), 0u);
  EXPECT_EQ(mailbox.posted(), 3u);
  EXPECT_EQ(mailbox.take(std::chrono::milliseconds(0), generation), nullptr);  // taken once only
}

TEST(FrameMailbox, BeyondTheBacklogTheOldestWaitingFramesGiveWay) {
  FrameMailbox mailbox(3, 3);
  for (uint32_t n = 1; n <= 7; ++n) post_frame(mailbox, n);
  EXPECT_EQ(mailbox.dropped(), 4u);  // 1..4: the newest always gets in
  EXPECT_EQ(take_all(mailbox), (std::vector<uint32_t>{5, 6, 7}));
  // Taking and posting interleaved: the slots cycle without loss.
  for (uint32_t n = 8; n < 40; ++n) {
    post_frame(mailbox, n);
    if (n % 2 == 0) post_frame(mailbox, 1000 + n);
    std::vector<uint32_t> expected{n};
    if (n % 2 == 0) expected.push_back(1000 + n);
    ASSERT_EQ(take_all(mailbox), expected);
  }
  EXPECT_EQ(mailbox.dropped(), 4u);
}

TEST(FrameMailbox, AFrameThatGivesWaySaysHowLongItWaitedAndWhenThePipelineLastTook) {
  FrameMailbox mailbox(3, 2);
  auto post = [&](uint32_t number) {
    mailbox.writable().frame_number = number;
    return mailbox.post(1);
  };
  EXPECT_FALSE(post(1));
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  EXPECT_FALSE(post(2));
  const auto stalled = post(3);  // nothing taken since the start: a stalled pipeline
  ASSERT_TRUE(stalled);
  EXPECT_EQ(stalled->frame_number, 1u);
  EXPECT_GE(stalled->waited, std::chrono::milliseconds(20));
  EXPECT_GE(stalled->since_last_take, stalled->waited);
  uint64_t generation = 0;
  ASSERT_NE(mailbox.take(std::chrono::milliseconds(0), generation), nullptr);  // frame 2
  EXPECT_FALSE(post(4));
  const auto burst = post(5);  // frame 3 was waiting before the take: the take is more recent
  ASSERT_TRUE(burst);
  EXPECT_EQ(burst->frame_number, 3u);
  EXPECT_LE(burst->since_last_take, burst->waited);
  EXPECT_EQ(mailbox.dropped(), 2u);
}

TEST(FrameMailbox, BacklogOfOneIsNewestFrameWins) {
  FrameMailbox mailbox(3, 1);
  post_frame(mailbox, 10);
  post_frame(mailbox, 11);
  post_frame(mailbox, 12);
  EXPECT_EQ(take_all(mailbox), (std::vector<uint32_t>{12}));
  EXPECT_EQ(mailbox.dropped(), 2u);
  EXPECT_THROW(FrameMailbox(3, 0), std::invalid_argument);
}

TEST(FrameMailbox, FrameTakenStaysIntactWhileTheWriterGoesOn) {
  FrameMailbox mailbox(3);
  post_frame(mailbox, 1);
  uint64_t generation = 0;
  const MarkerFrame* taken = mailbox.take(std::chrono::milliseconds(0), generation);
  for (uint32_t n = 2; n < 10; ++n) post_frame(mailbox, n);
  EXPECT_EQ(taken->frame_number, 1u);
  EXPECT_EQ(taken->labelled[0].x(), 1.0);
  EXPECT_EQ(mailbox.take(std::chrono::milliseconds(0), generation)->frame_number, 7u);
  EXPECT_EQ(mailbox.dropped(), 5u);  // 2..6 gave way to 7, 8 and 9
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
