// The pool of encoded frames: frames come back when the last reference goes, and an encoding's
// buffers can be made ahead on another thread so the pipeline thread never allocates them.
#include "server/pipeline/encoded_frame.h"

#include <gtest/gtest.h>

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

// Frames held by subscribers that stalled (the pool grew on the pipeline thread to 40) are
// freed once they come back, down to what the subscribers left need; frames still held stay.
TEST(FramePool, ResizeFreesTheFramesStalledSubscribersHeldOnceTheyAreBack) {
  FramePool pool(8);
  pool.prepare(3, 1000);
  std::vector<FrameRef> held;
  for (int i = 0; i < 40; ++i) held.push_back(pool.acquire());
  ASSERT_EQ(pool.allocated(), 40u);
  held.resize(12);  // 28 come back
  EXPECT_EQ(pool.resize(8), 0u);
  EXPECT_EQ(pool.allocated(), 12u) << "frames in use were freed, or free ones kept";
  EXPECT_EQ(pool.in_use(), 12u);
  held.clear();
  pool.resize(8);
  EXPECT_EQ(pool.allocated(), 8u);
  EXPECT_EQ(pool.in_use(), 0u);
}

// Grown ahead of the subscribers off the pipeline thread, the pool's new frames carry every
// prepared encoding: taking them allocates nothing there.
TEST(FramePool, ResizeGrowsWithThePreparedEncodingsSoThePipelineMakesNone) {
  FramePool pool(2);
  pool.prepare(3, 1000);
  pool.prepare(5, 2000);
  EXPECT_EQ(pool.resize(6), 8u);  // 4 new frames, 2 buffers each
  ASSERT_EQ(pool.allocated(), 6u);
  std::vector<FrameRef> frames;
  for (int i = 0; i < 6; ++i) frames.push_back(pool.acquire());
  const test::CountAllocations allocations;
  for (FrameRef& frame : frames) {
    EXPECT_FALSE(pool.size_message(*frame.mutable_frame(), 3, 1000));
    EXPECT_FALSE(pool.size_message(*frame.mutable_frame(), 5, 2000));
  }
  EXPECT_EQ(allocations.count(), 0u);
}

}  // namespace
}  // namespace skinstream::server
