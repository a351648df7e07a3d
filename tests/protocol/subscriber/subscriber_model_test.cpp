#include "protocol/subscriber/subscriber_model.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>

#include "support/subscriber_fixture.h"
#include "support/test_data.h"

namespace skinstream::subscriber {
namespace {

using test::payload_of;
using test::subscriber_fixture;

// model.bin, written from the spec by make_v2_fixtures.py: 3 vertices, 2 parts (2 and 1
// members), vertex 0 blended 0.75 / 0.25 between them.
TEST(SubscriberModel, MatchesGoldenBytesBothWays) {
  const std::vector<unsigned char> golden = subscriber_fixture("model.bin");
  const MessageHeader header = decode_header(golden);
  EXPECT_EQ(header.type, MessageType::Model);
  EXPECT_EQ(header.version, kVersion2);
  const EvaluationModel model = decode_model(payload_of(golden));
  EXPECT_EQ(model.vertex_count(), 3);
  ASSERT_EQ(model.part_count(), 2);
  EXPECT_EQ(model.member_count(), 3);
  EXPECT_EQ(model.parts[0].member_count, 2);
  EXPECT_EQ(model.parts[0].translation[0], -10.0f);
  EXPECT_EQ(model.parts[0].box_max[1], 5.0f);
  EXPECT_EQ(model.parts[0].sigma, 20.0f);
  EXPECT_EQ(model.parts[1].rotation[1], 1.0f);
  EXPECT_EQ(model.member_reference[3], 5.0f);
  EXPECT_EQ(model.influence_offsets, (std::vector<int>{0, 2, 3, 4}));
  EXPECT_EQ(model.influence_parts, (std::vector<int>{0, 1, 0, 1}));
  EXPECT_EQ(model.influence_weights, (std::vector<float>{0.75f, 0.25f, 1.0f, 1.0f}));
  EXPECT_TRUE(model.faces.empty());  // MeshInfo carries them
  EXPECT_EQ(encode_model(model), golden);
}

TEST(SubscriberModel, EveryTruncationAndExtensionIsRejected) {
  const std::vector<unsigned char> golden = subscriber_fixture("model.bin");
  for (size_t n = kHeaderBytes; n < golden.size(); ++n)
    EXPECT_THROW(decode_model(std::span(golden).subspan(kHeaderBytes, n - kHeaderBytes)), DecodeError) << "cut at " << n;
  std::vector<unsigned char> longer(golden.begin() + kHeaderBytes, golden.end());
  longer.push_back(0);
  EXPECT_THROW(decode_model(longer), DecodeError);
}

TEST(SubscriberModel, InconsistentModelsAreRejectedWithTheReason) {
  const std::vector<unsigned char> golden = subscriber_fixture("model.bin");
  auto expect_rejected = [&](size_t payload_offset, const void* value, size_t bytes, const char* reason) {
    std::vector<unsigned char> bad(golden.begin() + kHeaderBytes, golden.end());
    std::memcpy(bad.data() + payload_offset, value, bytes);
    try {
      decode_model(bad);
      FAIL() << "accepted a model with " << reason;
    } catch (const DecodeError& e) {
      EXPECT_NE(std::string(e.what()).find(reason), std::string::npos) << e.what();
    }
  };
  // Offsets in the payload: 16 counts, 36 vertices, 2 x 80 parts, 36 members, then the bytes.
  const size_t counts_at = 16 + 36 + 160 + 36;
  const uint32_t huge = 0x7FFFFFFF;
  expect_rejected(0, &huge, 4, "say");                          // vertex count against the payload
  expect_rejected(12, &huge, 4, "say");                         // influence count
  const uint8_t too_many = 3;
  expect_rejected(counts_at, &too_many, 1, "influences");       // the vertices count 5 influences, the header 4
  const uint8_t part_two = 2;
  expect_rejected(counts_at + 3 + 1, &part_two, 1, "part 2");   // vertex 0's second influence: part 2 of 2
  const float half = 0.5f;
  expect_rejected(counts_at + 8, &half, 4, "sum to");           // vertex 0's weights 0.5 + 0.25
  const float nan = std::nanf("");
  expect_rejected(16 + 4, &nan, 4, "not finite");               // a vertex coordinate
  const uint32_t members = 3;
  expect_rejected(16 + 36 + 76, &members, 4, "members");        // part 0 claims 3 of the 3
}

}  // namespace
}  // namespace skinstream::subscriber
