#include "protocol/subscriber/packed_message.h"

#include <gtest/gtest.h>

#include <cstring>
#include <random>

#include "support/subscriber_fixture.h"

namespace skinstream::subscriber {
namespace {

using test::payload_of;
using test::subscriber_fixture;

std::vector<unsigned char> plain_payload(const std::string& fixture) {
  const std::vector<unsigned char> message = subscriber_fixture(fixture);
  return {message.begin() + kHeaderBytes, message.end()};
}

// packed_*.bin are written from the spec by make_v2_fixtures.py (Python's own coding of the
// arrays, zlib at level 6): the encoder must make the same bytes and the decoder take them back.
TEST(PackedMessage, MatchesGoldenBytesBothWays) {
  for (const auto& [plain, packed, type] :
       {std::tuple{"mesh_info_v2.bin", "packed_mesh_info_v2.bin", MessageType::MeshInfo},
        std::tuple{"model.bin", "packed_model.bin", MessageType::Model}}) {
    const std::vector<unsigned char> golden = subscriber_fixture(packed);
    const MessageHeader header = decode_header(golden);
    EXPECT_EQ(header.type, MessageType::Packed);
    EXPECT_EQ(header.version, kVersion2);
    EXPECT_EQ(encode_packed(type, plain_payload(plain)), golden) << packed;
    const Unpacked unpacked = decode_packed(payload_of(golden));
    EXPECT_EQ(unpacked.type, type);
    EXPECT_EQ(plain_message_bytes(golden), subscriber_fixture(plain).size());
    EXPECT_EQ(unpacked.payload, plain_payload(plain)) << packed;
  }
}

// A body-sized MeshInfo: faces of a strip with neighbouring indices, as meshes have them.
std::vector<unsigned char> strip_mesh_info(uint32_t faces) {
  MeshInfo info;
  info.vertex_count = faces + 2;
  for (uint32_t f = 0; f < faces; ++f) info.faces.push_back({f, f + 1, f + 2});
  info.dominant_part.assign(info.vertex_count, 1);
  info.marker_names = {"LSHO", "RSHO"};
  info.marker_count = 2;
  info.subject = "Actor1";
  const std::vector<unsigned char> message = encode_mesh_info(info, kVersion2);
  return {message.begin() + kHeaderBytes, message.end()};
}

TEST(PackedMessage, AMeshsFacesComeBackExactlyInAFractionOfTheBytes) {
  const std::vector<unsigned char> plain = strip_mesh_info(100'000);
  const std::vector<unsigned char> packed = encode_packed(MessageType::MeshInfo, plain);
  EXPECT_LT(packed.size() * 20, plain.size())
      << "faces that differ by the same step each pack to almost nothing";
  const Unpacked unpacked = decode_packed(payload_of(packed));
  EXPECT_EQ(unpacked.payload, plain);
  EXPECT_EQ(decode_mesh_info(unpacked.payload, kVersion2).faces.size(), 100'000u);
}

TEST(PackedMessage, TheModelsFloatsComeBackBitForBit) {
  // Every bit pattern a float may have, NaNs and denormals among them: packing is lossless on
  // the bits, whatever they mean.
  std::mt19937 random(7);
  const uint32_t vertices = 5000;
  std::vector<unsigned char> plain(kPackedModelHeadBytes + 12 * vertices + 37);
  std::memcpy(plain.data(), &vertices, 4);
  for (size_t i = kPackedModelHeadBytes; i < plain.size(); ++i)
    plain[i] = static_cast<unsigned char>(random());
  const Unpacked unpacked = decode_packed(payload_of(encode_packed(MessageType::Model, plain, 1)));
  EXPECT_EQ(unpacked.type, MessageType::Model);
  EXPECT_EQ(unpacked.payload, plain);
}

TEST(PackedMessage, TheSourceRateChangesWithoutPackingAgain) {
  std::vector<unsigned char> packed = subscriber_fixture("packed_mesh_info_v2.bin");
  EXPECT_EQ(packed_source_rate(packed), 120.0f);
  set_packed_source_rate(packed, 239.76f);
  EXPECT_EQ(packed_source_rate(packed), 239.76f);
  EXPECT_EQ(decode_mesh_info(decode_packed(payload_of(packed)).payload, kVersion2).source_rate_hz, 239.76f);
}

TEST(PackedMessage, OnlyMeshInfoAndModelArePacked) {
  const std::vector<unsigned char> status = plain_payload("status_v2.bin");
  EXPECT_THROW(encode_packed(MessageType::Status, status), std::invalid_argument);
  std::vector<unsigned char> counts_too_big = plain_payload("model.bin");
  const uint32_t vertices = 1'000'000;
  std::memcpy(counts_too_big.data(), &vertices, 4);
  EXPECT_THROW(encode_packed(MessageType::Model, counts_too_big), std::invalid_argument);
}

void expect_refused(std::vector<unsigned char> payload, const std::string& reason,
                    uint32_t max_payload = kMaxPayloadBytes) {
  try {
    decode_packed(payload, max_payload);
    FAIL() << "accepted a Packed message with " << reason;
  } catch (const DecodeError& e) {
    EXPECT_NE(std::string(e.what()).find(reason), std::string::npos) << e.what();
  }
}

std::vector<unsigned char> golden_packed_payload() { return plain_payload("packed_mesh_info_v2.bin"); }

template <typename T>
std::vector<unsigned char> with_value(std::vector<unsigned char> payload, size_t offset, T value) {
  std::memcpy(payload.data() + offset, &value, sizeof value);
  return payload;
}

TEST(PackedMessage, EveryTruncationAndExtensionIsRefused) {
  const std::vector<unsigned char> golden = golden_packed_payload();
  for (size_t n = 0; n < golden.size(); ++n)
    EXPECT_THROW(decode_packed(std::span(golden).first(n)), DecodeError) << "cut at " << n;
  std::vector<unsigned char> longer = golden;
  longer.push_back(0);
  expect_refused(longer, "1 bytes after the deflated stream");
}

TEST(PackedMessage, ForgedFieldsAreRefusedWithTheReason) {
  const std::vector<unsigned char> golden = golden_packed_payload();
  expect_refused(with_value<uint16_t>(golden, 0, 3), "type 3 (only MeshInfo and Model are packed)");
  expect_refused(with_value<uint16_t>(golden, 2, 1), "reserved field is 1");
  expect_refused(with_value<uint32_t>(golden, 4, 100u << 20), "over the limit");
  expect_refused(golden, "over the limit of 64", 64);
  expect_refused(with_value<uint32_t>(golden, 4, 5), "shorter than its counts");
  expect_refused(with_value<uint32_t>(golden, 4, 60'000'000), "deflated bytes cannot make");
  expect_refused(with_value<uint32_t>(golden, 8 + 4, 1'000'000), "face count needs 12000000 bytes");
  const uint32_t unpacked = golden[4] | golden[5] << 8 | golden[6] << 16 | golden[7] << 24;
  expect_refused(with_value<uint32_t>(golden, 4, unpacked + 1), "the unpacked size says");
  expect_refused(with_value<uint32_t>(golden, 4, unpacked - 1), "makes more than the unpacked size");
  std::vector<unsigned char> corrupt = golden;
  corrupt[kPackedFieldsBytes + kPackedMeshInfoHeadBytes + 3] ^= 0xFF;
  EXPECT_THROW(decode_packed(corrupt), DecodeError);
}

}  // namespace
}  // namespace skinstream::subscriber
