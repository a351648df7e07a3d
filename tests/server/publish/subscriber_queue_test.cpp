#include "server/publish/subscriber_queue.h"

#include <gtest/gtest.h>

#include <thread>

#include "protocol/subscriber/subscriber_stream.h"
#include "support/allocation_counter.h"

namespace skinstream::server {
namespace {

FrameRef frame(FramePool& pool, uint32_t number) {
  FrameRef ref = pool.acquire();
  ref.mutable_frame()->frame_number = number;
  return ref;
}

ControlMessage status_message(uint64_t received) {
  subscriber::Status status;
  status.frames_received = received;
  return std::make_shared<const std::vector<unsigned char>>(subscriber::encode_status(status));
}

TEST(SubscriberQueue, NewestFramesWinAndDropsAreCounted) {
  FramePool pool;
  SubscriberQueue queue(2);
  for (uint32_t n = 1; n <= 5; ++n) queue.push_frame(frame(pool, n));
  EXPECT_EQ(queue.frames_dropped(), 3u);
  SubscriberQueue::Item item;
  ASSERT_TRUE(queue.pop(item));
  EXPECT_EQ(item.frame->frame_number, 4u);
  ASSERT_TRUE(queue.pop(item));
  EXPECT_EQ(item.frame->frame_number, 5u);
  EXPECT_FALSE(queue.pop(item));
}

// What a paced subscriber's pump takes: with its window full only control messages, then the
// newest frame, the older ones counted as dropped.
FrameRef frame_published(FramePool& pool, uint32_t number, std::chrono::steady_clock::time_point published) {
  FrameRef ref = frame(pool, number);
  ref.mutable_frame()->published = published;
  return ref;
}

TEST(SubscriberQueue, ABurstReadWithinTheWaitLimitArrivesWhole) {
  FramePool pool;
  SubscriberQueue queue(32, std::chrono::seconds(10));
  const auto now = std::chrono::steady_clock::now();
  for (uint32_t n = 1; n <= 20; ++n) queue.push_frame(frame_published(pool, n, now));
  SubscriberQueue::Item item;
  for (uint32_t n = 1; n <= 20; ++n) {
    ASSERT_TRUE(queue.pop(item));
    EXPECT_EQ(item.frame->frame_number, n);
  }
  EXPECT_EQ(queue.frames_dropped(), 0u);
}

TEST(SubscriberQueue, FramesOlderThanTheWaitLimitGiveWayToNewerOnes) {
  FramePool pool;
  SubscriberQueue queue(32, std::chrono::milliseconds(30));
  const auto now = std::chrono::steady_clock::now();
  // At the push: frames published a second ago give way to the new one.
  for (uint32_t n = 1; n <= 10; ++n) queue.push_frame(frame_published(pool, n, now - std::chrono::seconds(1)));
  EXPECT_EQ(queue.frames_queued(), 1u);  // a subscriber that never reads holds only the last
  queue.push_frame(frame_published(pool, 11, now));
  EXPECT_EQ(queue.frames_queued(), 1u);
  EXPECT_EQ(queue.frames_dropped(), 10u);
  SubscriberQueue::Item item;
  ASSERT_TRUE(queue.pop(item));
  EXPECT_EQ(item.frame->frame_number, 11u);
  // At the pop: 12 was young when 13 came, and is too old when the writer gets to it.
  queue.push_frame(frame_published(pool, 12, std::chrono::steady_clock::now() - std::chrono::milliseconds(20)));
  queue.push_frame(frame_published(pool, 13, std::chrono::steady_clock::now()));
  std::this_thread::sleep_for(std::chrono::milliseconds(15));
  ASSERT_TRUE(queue.pop(item));
  EXPECT_EQ(item.frame->frame_number, 13u);
  EXPECT_EQ(queue.frames_dropped(), 11u);
  // The newest is always taken, however old.
  queue.push_frame(frame_published(pool, 14, now - std::chrono::seconds(1)));
  ASSERT_TRUE(queue.pop(item));
  EXPECT_EQ(item.frame->frame_number, 14u);
}

TEST(SubscriberQueue, PacedTakesControlOnlyOrTheNewestFrame) {
  FramePool pool;
  SubscriberQueue queue(4);
  for (uint32_t n = 1; n <= 3; ++n) queue.push_frame(frame(pool, n));
  queue.push_control(status_message(7));
  SubscriberQueue::Item item;
  ASSERT_TRUE(queue.pop(item, SubscriberQueue::Take::ControlOnly));
  EXPECT_TRUE(item.control);
  EXPECT_FALSE(queue.pop(item, SubscriberQueue::Take::ControlOnly));
  EXPECT_FALSE(queue.has_control());
  EXPECT_EQ(queue.frames_dropped(), 0u);
  ASSERT_TRUE(queue.pop(item, SubscriberQueue::Take::NewestFrame));
  ASSERT_TRUE(item.frame);
  EXPECT_EQ(item.frame->frame_number, 3u);
  EXPECT_EQ(queue.frames_dropped(), 2u);
  EXPECT_FALSE(queue.pop(item, SubscriberQueue::Take::NewestFrame));
}

TEST(SubscriberQueue, DroppedFramesGoBackToThePool) {
  FramePool pool;
  {
    SubscriberQueue queue(2);
    for (uint32_t n = 1; n <= 50; ++n) queue.push_frame(frame(pool, n));
    EXPECT_LE(pool.allocated(), 3u);  // two queued, one being pushed: reused, not grown
  }
  // Steady state: pushing and popping allocates nothing.
  SubscriberQueue queue(2);
  SubscriberQueue::Item item;
  auto traffic = [&] {
    for (uint32_t n = 1; n <= 100; ++n) {
      queue.push_frame(frame(pool, n));
      if (n % 3 == 0) queue.pop(item);
    }
  };
  traffic();  // the pool grows to what is held at once (queued, popped, being pushed)
  const size_t pool_size = pool.allocated();
  test::CountAllocations allocations;
  traffic();
  EXPECT_EQ(allocations.count(), 0u);
  EXPECT_EQ(pool.allocated(), pool_size);
}

TEST(SubscriberQueue, ControlMessagesGoFirst) {
  FramePool pool;
  SubscriberQueue queue(4);
  queue.push_frame(frame(pool, 1));
  queue.push_control(status_message(7));
  SubscriberQueue::Item item;
  ASSERT_TRUE(queue.pop(item));
  ASSERT_TRUE(item.control);
  EXPECT_FALSE(item.frame);
  ASSERT_TRUE(queue.pop(item));
  EXPECT_EQ(item.frame->frame_number, 1u);
}

TEST(SubscriberQueue, TooManyStatusesDropTheOldestStatusNotTheMeshInfo) {
  SubscriberQueue queue(1);
  const ControlMessage mesh_info = std::make_shared<const std::vector<unsigned char>>(subscriber::encode_mesh_info({}));
  queue.push_control(mesh_info);
  for (uint64_t i = 0; i < 20; ++i) queue.push_control(status_message(i));
  SubscriberQueue::Item item;
  ASSERT_TRUE(queue.pop(item));
  EXPECT_EQ(item.control, mesh_info);
  uint64_t last = 0;
  int statuses = 0;
  while (queue.pop(item)) {
    ++statuses;
    last = subscriber::decode_status(std::span(*item.control).subspan(subscriber::kHeaderBytes)).frames_received;
  }
  EXPECT_EQ(statuses, static_cast<int>(SubscriberQueue::kMaxControl) - 1);
  EXPECT_EQ(last, 19u);  // the newest survived
}

}  // namespace
}  // namespace skinstream::server
