#include "protocol/subscriber/datagram_reassembler.h"

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
  EXPECT_EQ(r.stats().datagrams_rejected, 2u);
  // Another stream's datagrams are not an error, only not ours.
  EXPECT_FALSE(r.add(datagrams_of(1, 7788, 5)[1], t0));
  EXPECT_EQ(r.stats().datagrams_other_stream, 1u);
  std::optional<DatagramReassembler::Message> message;
  for (size_t i = 1; i < frame.size(); ++i) message = r.add(frame[i], t0);
  ASSERT_TRUE(message);
  EXPECT_TRUE(holds_message(message->bytes, 7788));
  EXPECT_EQ(message->header.model_id, 9u);
}

// Fragments whose count, size or model disagree with those of their sequence's others: one of
// them is not the sender's. They are put together apart, so neither a forged first fragment nor
// a forged copy of every real fragment (another model id) keeps the real frame out; the real one,
// complete, ends the other.
TEST(DatagramReassembler, FragmentsThatDisagreeArePutTogetherApart) {
  DatagramReassembler r({});
  const Clock::time_point t0{};
  EXPECT_FALSE(r.add(datagrams_of(1, 7000)[1], t0));       // forged: another size
  EXPECT_FALSE(r.add(datagrams_of(1, 7788, 0, 10)[0], t0));  // forged: another model
  const std::vector<ByteVector> real = datagrams_of(1), copies = datagrams_of(1, 7788, 0, 10);
  std::optional<DatagramReassembler::Message> message;
  for (size_t i = 0; i < real.size() && !message; ++i) {
    message = r.add(real[i], t0);
    if (!message && i > 0) {
      EXPECT_FALSE(r.add(copies[i], t0));  // each real fragment copied at once
    }
  }
  ASSERT_TRUE(message);
  EXPECT_TRUE(holds_message(message->bytes, 7788));
  EXPECT_EQ(message->header.model_id, 9u);
  EXPECT_EQ(r.stats().frames_disputed, 2u);
  EXPECT_EQ(r.stats().datagrams_rejected, 0u);
  EXPECT_FALSE(r.add(copies.back(), t0));  // the copy's last fragment: late
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
  // The stream goes on.
  std::optional<DatagramReassembler::Message> message;
  for (const ByteVector& d : datagrams_of(4)) message = r.add(d, t0 + milliseconds(25));
  EXPECT_TRUE(message);
}

// A daemon restarted counts from 0 again: once no frame of the old numbering completed for
// resync_after, the new one is followed.
TEST(DatagramReassembler, ASenderThatStartsAgainIsFollowed) {
  DatagramReassembler r({});
  const Clock::time_point t0{};
  for (const ByteVector& d : datagrams_of(500000)) r.add(d, t0);
  std::optional<DatagramReassembler::Message> message;
  for (const ByteVector& d : datagrams_of(0)) message = r.add(d, t0 + milliseconds(150));
  EXPECT_TRUE(message);
  EXPECT_EQ(r.stats().frames_completed, 2u);
  EXPECT_EQ(r.stats().resyncs, 1u);
}

// The stream at 120 Hz, from sequence `first`, for `frames` frames starting at `t`; `between`
// runs after each frame with its time. Returns the sequences completed.
template <typename Between>
std::vector<uint32_t> stream(DatagramReassembler& r, uint32_t first, int frames, Clock::time_point t, Between between) {
  std::vector<uint32_t> completed;
  for (int k = 0; k < frames; ++k) {
    const Clock::time_point now = t + std::chrono::microseconds(8333) * k;
    for (const ByteVector& d : datagrams_of(first + static_cast<uint32_t>(k)))
      if (const auto message = r.add(d, now)) completed.push_back(message->header.sequence);
    between(now);
  }
  return completed;
}

std::vector<uint32_t> sequences(uint32_t first, int count) {
  std::vector<uint32_t> out;
  for (int k = 0; k < count; ++k) out.push_back(first + static_cast<uint32_t>(k));
  return out;
}

// Copies of real datagrams far ahead (sequence + 1,200 once stopped frames for 10 s, + 60,000
// for good) or far behind, sent while the stream flows: counted, ignored, nothing lost.
TEST(DatagramReassembler, ForgedSequencesOutsideTheWindowCostNothing) {
  DatagramReassembler r({});
  uint32_t next_forged = 0;
  const std::vector<uint32_t> completed = stream(r, 1000, 240, Clock::time_point{}, [&](Clock::time_point now) {
    const uint32_t jumps[] = {1200, 60000, 0x80000000u, static_cast<uint32_t>(-500)};
    for (const ByteVector& d : datagrams_of(1000 + jumps[next_forged++ % 4])) r.add(d, now);
  });
  EXPECT_EQ(completed, sequences(1000, 240));
  EXPECT_EQ(r.stats().frames_lost, 0u);
  EXPECT_GT(r.stats().datagrams_out_of_window, 600u);
  EXPECT_GT(r.stats().datagrams_late, 300u);
  EXPECT_EQ(r.stats().resyncs, 0u);
}

// First fragments of frames that never come, at sequences just ahead (within the window), fast
// enough to fill every slot (about 360 a second once kept every real frame out): the frame due
// next keeps its slot, every real frame completes.
TEST(DatagramReassembler, ForgedFirstFragmentsDoNotKeepRealFramesOut) {
  DatagramReassembler r({});
  uint32_t sequence = 1000;
  const std::vector<uint32_t> completed = stream(r, 1000, 240, Clock::time_point{}, [&](Clock::time_point now) {
    ++sequence;
    for (uint32_t ahead = 2; ahead < 8; ++ahead) r.add(datagrams_of(sequence + ahead, 80000)[0], now);
  });
  EXPECT_EQ(completed, sequences(1000, 240));
  EXPECT_EQ(r.stats().frames_lost, 0u);
  EXPECT_GT(r.stats().datagrams_no_slot + r.stats().frames_incomplete, 240u);
}

// A whole forged frame just ahead completes (without a key it cannot be told from a real one):
// the real frames behind it are late, but for resync_after at most.
TEST(DatagramReassembler, AForgedFrameAheadCostsAtMostTheResyncTime) {
  DatagramReassembler r({});
  const Clock::time_point t0{};
  std::vector<uint32_t> completed = stream(r, 1000, 10, t0, [](Clock::time_point) {});
  for (const ByteVector& d : datagrams_of(1100)) r.add(d, t0 + milliseconds(80));  // forged, 100 frames ahead
  const std::vector<uint32_t> after = stream(r, 1010, 60, t0 + std::chrono::microseconds(8333) * 10, [](Clock::time_point) {});
  ASSERT_FALSE(after.empty());
  // Lost: the frames of the 100 ms after the forged one, 12 or 13 at 120 Hz; then the stream again.
  EXPECT_LE(after.front(), 1010u + 13u);
  EXPECT_EQ(after, sequences(after.front(), static_cast<int>(1070 - after.front())));
  EXPECT_EQ(r.stats().resyncs, 1u);
}

// With a key, only datagrams carrying its tag are taken: none without one, none of another key,
// none altered after signing; the signed stream completes without allocating.
TEST(DatagramReassembler, WithAKeyOnlyItsTaggedDatagramsAreTaken) {
  const std::string key = "stage-7 multicast key";
  const std::string other_key = "another stage's key!";
  auto authenticator = std::make_shared<DatagramAuthenticator>(std::span(reinterpret_cast<const unsigned char*>(key.data()), key.size()));
  const DatagramAuthenticator stranger(std::span(reinterpret_cast<const unsigned char*>(other_key.data()), other_key.size()));
  // Datagrams of a frame, signed by `signer` (null: not signed).
  auto signed_datagrams = [](uint32_t sequence, const DatagramAuthenticator* signer) {
    const size_t bytes = 7788;
    const uint16_t count = fragment_count(bytes, true);
    std::vector<ByteVector> out;
    for (uint16_t i = 0; i < count; ++i) {
      ByteVector d(kDatagramHeaderBytes);
      encode_datagram_header({0, 9, sequence, i, count, static_cast<uint32_t>(bytes), signer != nullptr},
                             std::span<unsigned char, kDatagramHeaderBytes>(d.data(), kDatagramHeaderBytes));
      for (size_t b = fragment_offset(bytes, count, i); b < fragment_offset(bytes, count, i) + fragment_bytes(bytes, count, i); ++b)
        d.push_back(static_cast<unsigned char>(b % 251));
      if (signer) {
        const std::span<const unsigned char> parts[] = {d};
        const DatagramTag tag = signer->tag(parts);
        d.insert(d.end(), tag.begin(), tag.end());
      }
      EXPECT_LE(d.size(), kMaxDatagramBytes);
      out.push_back(std::move(d));
    }
    return out;
  };
  DatagramReassembler r({.authenticator = authenticator});
  const Clock::time_point t0{};
  const std::vector<ByteVector> plain = datagrams_of(1), foreign = signed_datagrams(1, &stranger);
  std::vector<ByteVector> altered = signed_datagrams(1, authenticator.get());
  altered[0][16] ^= 1;  // the sequence, after signing
  for (const std::vector<ByteVector>* forged : {&plain, &foreign})
    for (const ByteVector& d : *forged) EXPECT_THROW(r.add(d, t0), DecodeError);
  EXPECT_THROW(r.add(altered[0], t0), DecodeError);
  EXPECT_EQ(r.stats().datagrams_unauthenticated, plain.size() + foreign.size() + 1);
  std::vector<std::vector<ByteVector>> frames;
  for (uint32_t s = 1; s <= 10; ++s) frames.push_back(signed_datagrams(s, authenticator.get()));
  const test::CountAllocations allocations;
  int completed = 0;
  for (const auto& frame : frames)
    for (const ByteVector& d : frame)
      if (const auto message = r.add(d, t0)) completed += holds_message(message->bytes, 7788) ? 1 : 0;
  EXPECT_EQ(allocations.count(), 0u);
  EXPECT_EQ(completed, 10);
}

}  // namespace
}  // namespace skinstream::subscriber
