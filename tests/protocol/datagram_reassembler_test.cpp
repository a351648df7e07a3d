#include "protocol/datagram_reassembler.h"

#include <gtest/gtest.h>

#include <cstring>

#include "support/allocation_counter.h"
#include "support/fixture_bytes.h"

namespace skinstream::subscriber {
namespace {

using test::ByteVector;
using Clock = DatagramReassembler::Clock;
using std::chrono::milliseconds;

// The datagrams of a message of `bytes` bytes (each byte its offset mod 251) for this sequence.
std::vector<ByteVector> datagrams_of(uint32_t sequence, size_t bytes = 7788, uint32_t stream = 0, uint32_t model = 9) {
  const uint16_t count = fragment_count(bytes);
  std::vector<ByteVector> out;
  for (uint16_t i = 0; i < count; ++i) {
    ByteVector d(kDatagramHeaderBytes);
    encode_datagram_header({stream, model, sequence, i, count, static_cast<uint32_t>(bytes)},
                           std::span<unsigned char, kDatagramHeaderBytes>(d.data(), kDatagramHeaderBytes));
    for (size_t b = fragment_offset(bytes, count, i); b < fragment_offset(bytes, count, i) + fragment_bytes(bytes, count, i); ++b)
      d.push_back(static_cast<unsigned char>(b % 251));
    out.push_back(std::move(d));
  }
  return out;
}

bool holds_message(std::span<const unsigned char> message, size_t bytes) {
  if (message.size() != bytes) return false;
  for (size_t b = 0; b < bytes; ++b)
    if (message[b] != b % 251) return false;
  return true;
}

TEST(DatagramReassembler, BadDatagramsAreCountedAndLeaveFramesInProgressAlone) {
  DatagramReassembler r({});
  const Clock::time_point t0{};
  const std::vector<ByteVector> frame = datagrams_of(1);
  EXPECT_FALSE(r.add(frame[0], t0));
  ByteVector truncated = frame[1];
  truncated.resize(100);
  EXPECT_THROW(r.add(truncated, t0), DecodeError);
  EXPECT_THROW(r.add(ByteVector(3, 0xFF), t0), DecodeError);  // foreign bytes on the group
  // The same frame's fragment with another size or model: inconsistent.
  const std::vector<ByteVector> other_size = datagrams_of(1, 7000);
  EXPECT_THROW(r.add(other_size[1], t0), DecodeError);
  const std::vector<ByteVector> other_model = datagrams_of(1, 7788, 0, 10);
  try {
    r.add(other_model[1], t0);
    FAIL() << "accepted a fragment of another model";
  } catch (const DecodeError& e) {
    EXPECT_NE(std::string(e.what()).find("disagrees"), std::string::npos) << e.what();
  }
  EXPECT_EQ(r.stats().datagrams_rejected, 4u);
  // Another stream's datagrams are not an error, only not ours.
  EXPECT_FALSE(r.add(datagrams_of(1, 7788, 5)[1], t0));
  EXPECT_EQ(r.stats().datagrams_other_stream, 1u);
  std::optional<DatagramReassembler::Message> message;
  for (size_t i = 1; i < frame.size(); ++i) message = r.add(frame[i], t0);
  ASSERT_TRUE(message);
  EXPECT_TRUE(holds_message(message->bytes, 7788));
  EXPECT_EQ(message->header.model_id, 9u);
}

TEST(DatagramReassembler, FragmentsInAnyOrderMakeTheMessageWithoutAllocating) {
  DatagramReassembler r({});
  std::vector<std::vector<ByteVector>> frames;
  for (uint32_t s = 10; s < 20; ++s) frames.push_back(datagrams_of(s));
  const test::CountAllocations allocations;
  int completed = 0;
  for (const auto& frame : frames) {
    // Last fragment first, then the rest backwards, each twice.
    for (size_t i = frame.size(); i-- > 0;) {
      const auto message = r.add(frame[i], Clock::time_point{});
      if (i == 0) {
        ASSERT_TRUE(message);
        ++completed;
        EXPECT_TRUE(holds_message(message->bytes, 7788));
      } else {
        EXPECT_FALSE(message);
      }
      EXPECT_FALSE(r.add(frame[i], Clock::time_point{}));  // a duplicate, or late once complete
    }
  }
  EXPECT_EQ(allocations.count(), 0u);
  EXPECT_EQ(completed, 10);
  EXPECT_EQ(r.stats().frames_completed, 10u);
  EXPECT_EQ(r.stats().frames_lost, 0u);
  EXPECT_EQ(r.stats().datagrams_duplicate, 50u);  // 5 of each frame's 6 came twice while it was in progress
  EXPECT_EQ(r.stats().datagrams_late, 10u);       // the completing one, again
}

TEST(DatagramReassembler, ALostDatagramCostsOnlyItsFrame) {
  DatagramReassembler r({});
  Clock::time_point now{};
  std::vector<uint32_t> completed;
  for (uint32_t s = 0; s < 30; ++s) {
    const std::vector<ByteVector> frame = datagrams_of(s);
    for (size_t i = 0; i < frame.size(); ++i) {
      if (s % 5 == 2 && i == 3) continue;  // lost on the way
      if (r.add(frame[i], now)) completed.push_back(s);
    }
    now += milliseconds(8);
  }
  EXPECT_EQ(completed.size(), 24u);
  for (uint32_t s : completed) EXPECT_NE(s % 5, 2u);
  EXPECT_EQ(r.stats().frames_lost, 6u);
  EXPECT_EQ(r.stats().frames_incomplete, 6u);
  // A fragment of a frame given up comes late: ignored, counted.
  EXPECT_FALSE(r.add(datagrams_of(27)[3], now));
  EXPECT_EQ(r.stats().datagrams_late, 1u);
}

TEST(DatagramReassembler, AFrameNotCompleteWithinTheWindowIsGivenUp) {
  DatagramReassembler r({.stream_id = 0, .window = milliseconds(20)});
  const std::vector<ByteVector> frame = datagrams_of(3);
  const Clock::time_point t0{};
  for (size_t i = 0; i + 1 < frame.size(); ++i) EXPECT_FALSE(r.add(frame[i], t0));
  r.expire(t0 + milliseconds(21));
  EXPECT_EQ(r.stats().frames_incomplete, 1u);
  EXPECT_FALSE(r.add(frame.back(), t0 + milliseconds(22)));  // too late to complete it
  EXPECT_EQ(r.stats().datagrams_late, 1u);
  // The stream goes on.
  std::optional<DatagramReassembler::Message> message;
  for (const ByteVector& d : datagrams_of(4)) message = r.add(d, t0 + milliseconds(25));
  EXPECT_TRUE(message);
}

TEST(DatagramReassembler, ASenderThatStartsAgainIsFollowed) {
  DatagramReassembler r({});
  for (const ByteVector& d : datagrams_of(500000)) r.add(d, Clock::time_point{});
  std::optional<DatagramReassembler::Message> message;
  for (const ByteVector& d : datagrams_of(0)) message = r.add(d, Clock::time_point{});
  EXPECT_TRUE(message);
  EXPECT_EQ(r.stats().frames_completed, 2u);
}

}  // namespace
}  // namespace skinstream::subscriber
