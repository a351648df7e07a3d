// The pool of encoded frames: frames come back when the last reference goes, and an encoding's
// buffers can be made ahead on another thread so the pipeline thread never allocates them.
#include "server/pipeline/encoded_frame.h"

#include <gtest/gtest.h>

#include <chrono>
#include <thread>
#include <vector>

#include "support/allocation_counter.h"

namespace skinstream::server {
namespace {

TEST(FramePool, AFrameGoesBackWhenItsLastReferenceGoes) {
  FramePool pool(2);
  FrameRef a = pool.acquire();
  FrameRef copy = a;
  a.reset();
  FrameRef b = pool.acquire();
  FrameRef c = pool.acquire();  // `copy` still holds the first: the pool grows
  EXPECT_EQ(pool.allocated(), 3u);
  const EncodedFrame* first = copy.operator->();
  copy.reset();
  EXPECT_EQ(pool.acquire().operator->(), first);
}

TEST(FramePool, PreparedBuffersAreTakenWithoutAllocating) {
  constexpr size_t kBytes = 640 * 1024;
  constexpr uint32_t kFlags = 3;
  FramePool pool(4);
  // Made on another thread, as the daemon does when a subscriber says Hello.
  size_t made = 0;
  std::thread([&] { made = pool.prepare(kFlags, kBytes); }).join();
  EXPECT_EQ(made, 4u);
  EXPECT_EQ(pool.prepare(kFlags, kBytes), 0u) << "every frame already has one waiting";

  std::vector<FrameRef> held;
  held.reserve(5);
  {
    test::CountAllocations allocations;
    for (int i = 0; i < 4; ++i) {
      held.push_back(pool.acquire());  // room reserved above
      EXPECT_FALSE(pool.size_message(*held.back().mutable_frame(), kFlags, kBytes));
      EXPECT_EQ(held.back()->message(kFlags).size(), kBytes);
    }
    EXPECT_EQ(allocations.count(), 0u);
  }
  // A second take on a sized frame is free; a fifth frame (the pool grew) has nothing prepared.
  EXPECT_FALSE(pool.size_message(*held.front().mutable_frame(), kFlags, kBytes));
  FrameRef fifth = pool.acquire();
  EXPECT_TRUE(pool.size_message(*fifth.mutable_frame(), kFlags, kBytes));
  EXPECT_EQ(fifth->message(kFlags).size(), kBytes);
  // Only the frames without that encoding count as missing, and another encoding is separate.
  EXPECT_EQ(pool.prepare(kFlags, kBytes), 0u);
  EXPECT_EQ(pool.prepare(0, 1000), 5u);
  EXPECT_EQ(pool.prepare(EncodedFrame::kEncodings, 1000), 0u) << "no such encoding";
}

// Frames held by subscribers that stalled (the pool grew to 40) are freed once they come back,
// down to the most in use at once since the last trim plus the free frames asked for; frames
// still held stay.
TEST(FramePool, TrimFreesTheFramesStalledSubscribersHeldOnceTheyAreBack) {
  FramePool pool(8);
  pool.prepare(3, 1000);
  std::vector<FrameRef> held;
  for (int i = 0; i < 40; ++i) held.push_back(pool.acquire());
  ASSERT_EQ(pool.allocated(), 40u);
  EXPECT_EQ(pool.in_use_high_water(), 40u);
  held.resize(12);  // 28 come back
  EXPECT_EQ(pool.trim(4), 0u) << "40 were in use since the last trim: all are kept";
  EXPECT_EQ(pool.in_use_high_water(), 12u) << "the high water mark starts again from the frames in use";
  EXPECT_EQ(pool.trim(4), 24u);
  EXPECT_EQ(pool.allocated(), 16u) << "12 in use and 4 free";
  EXPECT_EQ(pool.in_use(), 12u);
  held.clear();
  pool.trim(4);
  EXPECT_EQ(pool.allocated(), 16u) << "12 in use since the last trim";
  pool.trim(4);
  EXPECT_EQ(pool.allocated(), 4u);
  EXPECT_EQ(pool.in_use(), 0u);
}

// A frame taken and given back between two trims counts in the high water mark: a subscriber's
// frame in flight at the moment of the trim, or between two, is not freed under the pool's feet.
TEST(FramePool, TheHighWaterMarkCountsFramesHeldBetweenTrims) {
  FramePool pool(2);
  {
    std::vector<FrameRef> burst;
    for (int i = 0; i < 10; ++i) burst.push_back(pool.acquire());
  }
  EXPECT_EQ(pool.in_use(), 0u);
  EXPECT_EQ(pool.trim(2), 0u);
  EXPECT_EQ(pool.allocated(), 10u);
  EXPECT_EQ(pool.trim(2), 8u);
  EXPECT_EQ(pool.allocated(), 2u);
}

// Grown ahead of the subscribers off the pipeline thread, the pool's new frames carry every
// prepared encoding: taking them allocates nothing there.
TEST(FramePool, KeepFreeGrowsWithThePreparedEncodingsSoThePipelineMakesNone) {
  FramePool pool(2);
  pool.prepare(3, 1000);
  pool.prepare(5, 2000);
  FrameRef held = pool.acquire();
  EXPECT_EQ(pool.keep_free(6), 10u);  // 5 new frames, 2 buffers each
  ASSERT_EQ(pool.allocated(), 7u);
  EXPECT_EQ(pool.free_count(), 6u);
  EXPECT_EQ(pool.keep_free(6), 0u) << "6 are free already";
  std::vector<FrameRef> frames;
  frames.reserve(6);
  const test::CountAllocations allocations;
  for (int i = 0; i < 6; ++i) {
    frames.push_back(pool.acquire());
    EXPECT_FALSE(pool.size_message(*frames.back().mutable_frame(), 3, 1000));
    EXPECT_FALSE(pool.size_message(*frames.back().mutable_frame(), 5, 2000));
  }
  EXPECT_EQ(allocations.count(), 0u);
  EXPECT_EQ(pool.allocated(), 7u);
}

// An encoding asked for once (a Hello flooder cycling through the flags) keeps its buffers only
// while someone wants it and for the hold-off after: then those of the free frames and the
// prepared ones are freed, keep_free() stops making them, a frame still held keeps its own until
// it is free, and asking again makes them anew off the pipeline thread.
TEST(FramePool, BuffersOfAnEncodingNobodyWantsAreFreedAfterTheHoldOff) {
  using namespace std::chrono_literals;
  constexpr StreamKey kWanted = 3, kDropped = 5;
  constexpr auto kHoldOff = 10s;
  FramePool pool(4);
  pool.prepare(kWanted, 1000);
  pool.prepare(kDropped, 2000);
  FrameRef held = pool.acquire();
  ASSERT_FALSE(pool.size_message(*held.mutable_frame(), kDropped, 2000));
  StreamKeySet wanted;
  wanted.add(kWanted);
  const auto now = std::chrono::steady_clock::now();
  EXPECT_EQ(pool.release_unwanted(wanted, now, kHoldOff), 0u) << "asked for just now";
  EXPECT_EQ(pool.release_unwanted(wanted, now + 11s, kHoldOff), 3u) << "the 3 prepared for the free frames";
  EXPECT_EQ(pool.keep_free(8), 5u) << "5 new frames, each with the wanted encoding only";
  held.reset();
  EXPECT_EQ(pool.release_unwanted(wanted, now + 12s, kHoldOff), 1u) << "the held frame's, now that it is free";
  EXPECT_EQ(pool.release_unwanted(wanted, now + 60s, kHoldOff), 0u) << "the wanted encoding keeps its buffers";
  EXPECT_EQ(pool.prepare(kDropped, 2000), 9u) << "asked for again: made for every frame";
  EXPECT_EQ(pool.release_unwanted(wanted, std::chrono::steady_clock::now() + 1s, kHoldOff), 0u);
  std::vector<FrameRef> frames;
  frames.reserve(9);
  const test::CountAllocations allocations;
  for (int i = 0; i < 9; ++i) {
    frames.push_back(pool.acquire());
    EXPECT_FALSE(pool.size_message(*frames.back().mutable_frame(), kWanted, 1000));
    EXPECT_FALSE(pool.size_message(*frames.back().mutable_frame(), kDropped, 2000));
  }
  EXPECT_EQ(allocations.count(), 0u);
}

// The pipeline takes the pool's lock for every frame: release_unwanted() sizes its list of
// buffers to free before it takes that lock, so it allocates once however many it frees
// (growing the list inside the lock took one allocation per doubling, each under the lock).
TEST(FramePool, ReleasingUnwantedBuffersAllocatesOnceBeforeTakingTheLock) {
  using namespace std::chrono_literals;
  constexpr StreamKey kDropped = 5;
  FramePool pool(40);
  pool.prepare(kDropped, 100);
  const auto now = std::chrono::steady_clock::now();
  size_t freed = 0;
  size_t allocated = 0;
  {
    const test::CountAllocations allocations;
    freed = pool.release_unwanted(StreamKeySet{}, now + 11s, 10s);
    allocated = allocations.count();
  }
  EXPECT_EQ(freed, 40u);
  EXPECT_EQ(allocated, 1u);
}

}  // namespace
}  // namespace skinstream::server
