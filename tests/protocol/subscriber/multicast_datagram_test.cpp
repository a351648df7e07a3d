#include "protocol/subscriber/multicast_datagram.h"

#include <gtest/gtest.h>

#include <cstring>

#include "protocol/subscriber/frame_parameters.h"
#include "support/fixture_bytes.h"

namespace skinstream::subscriber {
namespace {

using test::ByteVector;
using test::fixture_bytes;

std::string rejection(const ByteVector& datagram) {
  try {
    decode_datagram_header(datagram);
    return "accepted";
  } catch (const DecodeError& e) {
    return e.what();
  }
}

template <typename T>
ByteVector with(ByteVector bytes, size_t offset, T value) {
  std::memcpy(bytes.data() + offset, &value, sizeof value);
  return bytes;
}

TEST(MulticastDatagram, BadDatagramsAreRejectedWithTheRuleTheyBreak) {
  const ByteVector good = fixture_bytes("multicast/datagram_0.bin");
  EXPECT_NE(rejection(ByteVector(good.begin(), good.begin() + 27)).find("shorter than its 28-byte header"), std::string::npos);
  ByteVector oversized = good;
  oversized.resize(kMaxDatagramBytes + 1);
  EXPECT_NE(rejection(oversized).find("over the 1400"), std::string::npos);
  EXPECT_NE(rejection(with<uint32_t>(good, 0, 0x46534B53)).find("bad magic"), std::string::npos);  // a TCP message's magic
  EXPECT_NE(rejection(with<uint16_t>(good, 4, 2)).find("version 2"), std::string::npos);
  EXPECT_NE(rejection(with<uint16_t>(good, 6, 4)).find("reserved"), std::string::npos);
  EXPECT_NE(rejection(with<uint16_t>(good, 6, kDatagramAuthenticated)).find("holds 932 bytes, not 964"), std::string::npos);  // no tag
  EXPECT_NE(rejection(with<uint16_t>(good, 20, 2)).find("fragment 2 of 2"), std::string::npos);
  EXPECT_NE(rejection(with<uint16_t>(good, 22, 0)).find("fragment count 0"), std::string::npos);
  EXPECT_NE(rejection(with<uint16_t>(good, 22, 65)).find("fragment count 65"), std::string::npos);
  EXPECT_NE(rejection(with<uint32_t>(good, 24, 0)).find("cannot be cut"), std::string::npos);
  EXPECT_NE(rejection(with<uint32_t>(good, 24, 5000)).find("cannot be cut into 2"), std::string::npos);  // 2,500-byte fragments
  EXPECT_NE(rejection(with<uint32_t>(good, 24, 1930)).find("holds 964 bytes, not 965"), std::string::npos);
  ByteVector truncated = good;
  truncated.pop_back();
  EXPECT_NE(rejection(truncated).find("holds 963 bytes, not 964"), std::string::npos);
  for (const ByteVector& bad : {truncated, oversized}) EXPECT_EQ(rejection(bad).find('\n'), std::string::npos);
}

// datagram_0.bin and datagram_1.bin, written from the spec by make_fixtures.py: the two halves
// of frame.bin, a 1,928-byte parameter Frame message.
TEST(MulticastDatagram, MatchesGoldenBytesBothWays) {
  const ByteVector message = fixture_bytes("multicast/frame.bin");
  ASSERT_EQ(message.size(), 1928u);
  const uint16_t count = fragment_count(message.size());
  ASSERT_EQ(count, 2);
  for (uint16_t i = 0; i < count; ++i) {
    const ByteVector golden = fixture_bytes("multicast/datagram_" + std::to_string(i) + ".bin");
    const DatagramHeader h = decode_datagram_header(golden);
    EXPECT_EQ(h.stream_id, 2u);
    EXPECT_EQ(h.model_id, 0x1234ABCDu);
    EXPECT_EQ(h.sequence, 77u);
    EXPECT_EQ(h.index, i);
    EXPECT_EQ(h.count, 2);
    EXPECT_EQ(h.message_bytes, 1928u);
    ByteVector encoded(kDatagramHeaderBytes);
    encode_datagram_header(h, std::span<unsigned char, kDatagramHeaderBytes>(encoded.data(), kDatagramHeaderBytes));
    const size_t offset = fragment_offset(message.size(), count, i);
    encoded.insert(encoded.end(), message.begin() + offset, message.begin() + offset + fragment_bytes(message.size(), count, i));
    EXPECT_EQ(encoded, golden);
  }
  // The message itself is a version 2 parameter Frame as TCP carries it.
  const MessageHeader header = decode_header(message);
  EXPECT_EQ(header.type, MessageType::Frame);
  const FrameView view = view_frame(std::span(message).subspan(kHeaderBytes), kVersion2);
  EXPECT_EQ(view.info.flags, kFrameParameters);
  EXPECT_EQ(view.positions.size(), parameter_block_bytes(10, 20));
}

// offer_0.bin, written from the spec by make_fixtures.py: the offer of the subscriber fixtures'
// packed MeshInfo and Model, in one datagram with the offer flag.
TEST(MulticastDatagram, TheOffersDatagramMatchesGoldenBytesBothWays) {
  const ByteVector golden = fixture_bytes("multicast/offer_0.bin");
  const DatagramHeader h = decode_datagram_header(golden);
  EXPECT_TRUE(h.offer);
  EXPECT_FALSE(h.authenticated);
  EXPECT_EQ(h.sequence, 3u);  // its edition
  EXPECT_EQ(h.count, 1);
  EXPECT_EQ(h.message_bytes, golden.size() - kDatagramHeaderBytes);
  const ByteVector model = fixture_bytes("subscriber/model.bin");
  EXPECT_EQ(h.model_id, model_id_of(std::span(model).subspan(kHeaderBytes)));
  ByteVector encoded(kDatagramHeaderBytes);
  encode_datagram_header(
      h, std::span<unsigned char, kDatagramHeaderBytes>(encoded.data(), kDatagramHeaderBytes));
  EXPECT_TRUE(std::equal(encoded.begin(), encoded.end(), golden.begin()));
}

// A frame is at most 64 datagrams; the offer, which holds a whole body, 4,096.
TEST(MulticastDatagram, TheOfferMayBeCutIntoMoreFragmentsThanAFrame) {
  const size_t offer_bytes = 837'036;  // the demo body's packed MeshInfo and Model
  EXPECT_EQ(fragment_count(offer_bytes), 0);
  const uint16_t count = fragment_count(offer_bytes, false, kMaxOfferFragments);
  EXPECT_EQ(count, 611);
  EXPECT_EQ(fragment_count(size_t{kMaxOfferFragments} * kMaxFragmentBytes + 1, false, kMaxOfferFragments), 0);
  EXPECT_EQ(fragment_count(size_t{kMaxOfferFragments} * kMaxAuthenticatedFragmentBytes + 1, true,
                           kMaxOfferFragments),
            0);
  const DatagramHeader last{
      1, 2, 3, static_cast<uint16_t>(count - 1), count, static_cast<uint32_t>(offer_bytes), false, true};
  ByteVector datagram(kDatagramHeaderBytes);
  encode_datagram_header(
      last, std::span<unsigned char, kDatagramHeaderBytes>(datagram.data(), kDatagramHeaderBytes));
  datagram.resize(kDatagramHeaderBytes + fragment_bytes(offer_bytes, count, last.index));
  EXPECT_EQ(rejection(datagram), "accepted");
  // The same count without the offer flag is a frame's, and too many.
  EXPECT_NE(rejection(with<uint16_t>(datagram, 6, 0)).find("fragment count 611 (1-64)"), std::string::npos);
  EXPECT_NE(rejection(with<uint16_t>(datagram, 22, 4097)).find("fragment count 4097 (1-4096)"),
            std::string::npos);
}

TEST(MulticastDatagram, EveryFragmentFitsADatagramAndNoneIsEmpty) {
  EXPECT_EQ(fragment_count(0), 0);
  EXPECT_EQ(fragment_count(kMaxDatagramMessageBytes + 1), 0);
  for (size_t bytes : {size_t{1}, kMaxFragmentBytes, kMaxFragmentBytes + 1, size_t{7788}, size_t{40000}, kMaxDatagramMessageBytes}) {
    const uint16_t count = fragment_count(bytes);
    ASSERT_GE(count, 1) << bytes;
    size_t covered = 0;
    for (uint16_t i = 0; i < count; ++i) {
      EXPECT_EQ(fragment_offset(bytes, count, i), covered);
      EXPECT_GT(fragment_bytes(bytes, count, i), 0u);
      EXPECT_LE(fragment_bytes(bytes, count, i), kMaxFragmentBytes);
      covered += fragment_bytes(bytes, count, i);
    }
    EXPECT_EQ(covered, bytes);
  }
  EXPECT_EQ(fragment_count(7788), 6);  // the demo subject's frame: 17 parts, 415 members
}

TEST(MulticastDatagram, ModelIdIsTheCrcOfTheModelPayload) {
  const ByteVector model = fixture_bytes("subscriber/model.bin");
  const uint32_t id = model_id_of(std::span(model).subspan(kHeaderBytes));
  ByteVector changed = model;
  changed.back() ^= 1;
  EXPECT_NE(model_id_of(std::span(changed).subspan(kHeaderBytes)), id);
  EXPECT_EQ(model_id_of(std::span(model).subspan(kHeaderBytes)), id);
}

}  // namespace
}  // namespace skinstream::subscriber
