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
  FrameMailbox mailbox(3, std::chrono::seconds(10), 32);
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

// A source that held its frames for a while and then sends them back to back: the pipeline
// gets every one, however many, as long as it takes them within max_wait.
TEST(FrameMailbox, ABurstIsTakenWholeWithinTheWaitLimit) {
  FrameMailbox mailbox(3, std::chrono::seconds(10), 32);
  std::vector<uint32_t> expected;
  for (uint32_t n = 1; n <= 30; ++n) {
    post_frame(mailbox, n);
    expected.push_back(n);
  }
  EXPECT_EQ(take_all(mailbox), expected);
  EXPECT_EQ(mailbox.dropped(), 0u);
}

TEST(FrameMailbox, FramesThatWaitedTooLongGiveWayButTheNewestIsAlwaysTaken) {
  FrameMailbox mailbox(3, std::chrono::milliseconds(10), 32);
  post_frame(mailbox, 1);
  post_frame(mailbox, 2);
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  post_frame(mailbox, 3);
  EXPECT_EQ(take_all(mailbox), (std::vector<uint32_t>{3}));  // 1 and 2 waited 20 ms
  EXPECT_EQ(mailbox.dropped_waited_too_long(), 2u);
  post_frame(mailbox, 4);
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  EXPECT_EQ(take_all(mailbox), (std::vector<uint32_t>{4}));  // old, but nothing newer
  EXPECT_EQ(mailbox.dropped(), 2u);
  EXPECT_EQ(mailbox.dropped_mailbox_full(), 0u);
}

TEST(FrameMailbox, BeyondItsCapacityTheOldestWaitingFramesGiveWay) {
  FrameMailbox mailbox(3, std::chrono::seconds(10), 3);
  for (uint32_t n = 1; n <= 7; ++n) post_frame(mailbox, n);
  EXPECT_EQ(mailbox.dropped_mailbox_full(), 4u);  // 1..4: the newest always gets in
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
  EXPECT_EQ(mailbox.dropped_waited_too_long(), 0u);
}

// A subject swapped: its new mailbox carries on the counts of the one it replaces.
TEST(FrameMailbox, AReplacementAddsTheCountsOfTheMailboxItReplaces) {
  FrameMailbox old(3, std::chrono::seconds(10), 3);
  for (uint32_t n = 1; n <= 7; ++n) post_frame(old, n);
  FrameMailbox next(3, std::chrono::seconds(10), 3);
  for (uint32_t n = 8; n <= 12; ++n) post_frame(next, n);
  next.add_counts_of(old);
  EXPECT_EQ(next.dropped_mailbox_full(), 4u + 2u);
  EXPECT_EQ(next.dropped(), 6u);
  EXPECT_EQ(next.posted(), 12u);
  EXPECT_EQ(take_all(next), (std::vector<uint32_t>{10, 11, 12}));
}

TEST(FrameMailbox, WaitLimitOfZeroIsNewestFrameWins) {
  FrameMailbox mailbox(3, std::chrono::nanoseconds(0), 32);
  post_frame(mailbox, 10);
  post_frame(mailbox, 11);
  post_frame(mailbox, 12);
  EXPECT_EQ(take_all(mailbox), (std::vector<uint32_t>{12}));
  EXPECT_EQ(mailbox.dropped(), 2u);
  EXPECT_THROW(FrameMailbox(3, std::chrono::milliseconds(25), 0), std::invalid_argument);
  EXPECT_THROW(FrameMailbox(3, std::chrono::milliseconds(-1), 32), std::invalid_argument);
}

TEST(FrameMailbox, AFrameThatGivesWayIsReportedOnceWithWhyAndHowLongItWaited) {
  FrameMailbox mailbox(3, std::chrono::milliseconds(200), 2);
  auto post = [&](uint32_t number) {
    mailbox.writable().frame_number = number;
    return mailbox.post(1);
  };
  EXPECT_FALSE(post(1));
  std::this_thread::sleep_for(std::chrono::milliseconds(30));
  EXPECT_FALSE(post(2));
  const auto full = post(3);  // nothing taken since the start, the mailbox holds 2
  ASSERT_TRUE(full);
  EXPECT_EQ(full->frame_number, 1u);
  EXPECT_EQ(full->reason, FrameMailbox::DropReason::kMailboxFull);
  EXPECT_GE(full->waited, std::chrono::milliseconds(30));
  EXPECT_GE(full->since_last_take, full->waited);
  uint64_t generation = 0;
  ASSERT_EQ(mailbox.take(std::chrono::milliseconds(0), generation)->frame_number, 2u);
  EXPECT_FALSE(post(4));  // reported once
  std::this_thread::sleep_for(std::chrono::milliseconds(250));
  ASSERT_EQ(mailbox.take(std::chrono::milliseconds(0), generation)->frame_number, 4u);  // 3 waited 250 ms
  const auto late = post(5);  // the drop at the take is reported to the producer
  ASSERT_TRUE(late);
  EXPECT_EQ(late->frame_number, 3u);
  EXPECT_EQ(late->reason, FrameMailbox::DropReason::kWaitedTooLong);
  EXPECT_GE(late->waited, std::chrono::milliseconds(250));
  EXPECT_EQ(mailbox.dropped(), 2u);
}

TEST(FrameMailbox, FrameTakenStaysIntactWhileTheWriterGoesOn) {
  FrameMailbox mailbox(3, std::chrono::seconds(10), 3);
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
