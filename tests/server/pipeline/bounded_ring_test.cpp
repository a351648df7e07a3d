#include "server/pipeline/bounded_ring.h"

#include <gtest/gtest.h>

#include "support/allocation_counter.h"

namespace skinstream::server {
namespace {

// First in, first out across the wrap of the storage, full at its capacity, and pushing and
// popping allocate nothing.
TEST(BoundedRing, FirstInFirstOutAcrossTheWrapWithoutAllocating) {
  BoundedRing<int> ring(3);
  EXPECT_TRUE(ring.empty());
  size_t allocations = 0;
  {
    test::CountAllocations counter;
    ring.push(1);
    ring.push(2);
    EXPECT_EQ(ring.pop(), 1);
    ring.push(3);
    ring.push(4);  // wraps
    EXPECT_TRUE(ring.full());
    EXPECT_EQ(ring.size(), 3u);
    EXPECT_EQ(ring.pop(), 2);
    EXPECT_EQ(ring.pop(), 3);
    ring.push(5);
    EXPECT_EQ(ring.pop(), 4);
    EXPECT_EQ(ring.pop(), 5);
    allocations = counter.count();
  }
  EXPECT_TRUE(ring.empty());
  EXPECT_EQ(allocations, 0u);
}

TEST(BoundedRing, ResetEmptiesAndResizes) {
  BoundedRing<int> ring(1);
  ring.push(7);
  EXPECT_TRUE(ring.full());
  ring.reset(2);
  EXPECT_TRUE(ring.empty());
  ring.push(8);
  ring.push(9);
  EXPECT_TRUE(ring.full());
  EXPECT_EQ(ring.pop(), 8);
  EXPECT_EQ(ring.pop(), 9);
}

}  // namespace
}  // namespace skinstream::server
