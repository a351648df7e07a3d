#include "protocol/stream_buffer.h"

#include <gtest/gtest.h>

#include <numeric>
#include <vector>

#include "support/allocation_counter.h"

namespace skinstream {
namespace {

std::vector<unsigned char> count_from(unsigned char first, size_t n) {
  std::vector<unsigned char> bytes(n);
  std::iota(bytes.begin(), bytes.end(), first);
  return bytes;
}

TEST(StreamBuffer, WhatIsCommittedIsUnreadUntilConsumed) {
  StreamBuffer stream;
  const std::span<unsigned char> room = stream.prepare(10);
  ASSERT_EQ(room.size(), 10u);
  const std::vector<unsigned char> bytes = count_from(1, 6);
  std::copy(bytes.begin(), bytes.end(), room.begin());
  stream.commit(6);  // a read that filled part of the room
  EXPECT_EQ(std::vector<unsigned char>(stream.unread().begin(), stream.unread().end()), bytes);
  stream.consume(4);
  EXPECT_EQ(stream.buffered(), 2u);
  EXPECT_EQ(stream.unread()[0], 5);
  stream.feed(count_from(7, 3));
  EXPECT_EQ(std::vector<unsigned char>(stream.unread().begin(), stream.unread().end()), count_from(5, 5));
  stream.consume(100);  // never past what arrived
  EXPECT_EQ(stream.buffered(), 0u);
  stream.commit(1000);  // never past the room
  EXPECT_LE(stream.buffered(), stream.capacity());
}

TEST(StreamBuffer, AnUnreadTailMovesToTheFrontOnlyWhenTheRoomDoesNotFitBehindIt) {
  StreamBuffer stream;
  stream.reserve(16);
  stream.feed(count_from(0, 12));
  stream.consume(10);  // a partial message of 2 bytes is left
  const unsigned char* tail = stream.unread().data();
  stream.prepare(4);  // fits behind it: nothing moves
  EXPECT_EQ(stream.unread().data(), tail);
  stream.prepare(8);  // does not: the tail goes to the front, and the storage does not grow
  EXPECT_EQ(stream.capacity(), 16u);
  EXPECT_EQ(stream.unread()[0], 10);
  EXPECT_EQ(stream.unread()[1], 11);
  stream.prepare(20);  // cannot fit at all: grows, the tail kept
  EXPECT_GE(stream.capacity(), 22u);
  EXPECT_EQ(stream.unread()[1], 11);
  stream.clear();
  EXPECT_EQ(stream.buffered(), 0u);
}

// Messages of steady size, each read in two pieces that cut them anywhere: after the first
// rounds the buffer never allocates.
TEST(StreamBuffer, MessagesOfSteadySizeStopAllocating) {
  StreamBuffer stream;
  const std::vector<unsigned char> message = count_from(0, 1000);
  auto round = [&](size_t cut) {
    stream.feed(std::span(message).first(cut));
    stream.feed(std::span(message).subspan(cut));
    while (stream.buffered() >= 600) stream.consume(600);  // cut into 600-byte messages
  };
  for (size_t cut = 1; cut < message.size(); ++cut) round(cut);
  test::CountAllocations allocations;
  for (size_t cut = 1; cut < message.size(); cut += 7) round(cut);
  EXPECT_EQ(allocations.count(), 0u);
}

}  // namespace
}  // namespace skinstream
