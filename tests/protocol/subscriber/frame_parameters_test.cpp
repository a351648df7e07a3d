#include "protocol/subscriber/frame_parameters.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>

#include "support/allocation_counter.h"
#include "support/test_data.h"

namespace skinstream::subscriber {
namespace {

// The parameter block of frame_v2_parameters.bin (written from the spec by make_v2_fixtures.py).
std::vector<unsigned char> golden_block() {
  std::ifstream in(test::source_path("tests/protocol/fixtures/subscriber/frame_v2_parameters.bin"), std::ios::binary);
  const std::vector<unsigned char> message{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  const size_t at = kHeaderBytes + frame_info_bytes(kVersion2);
  return {message.begin() + static_cast<std::ptrdiff_t>(at), message.begin() + static_cast<std::ptrdiff_t>(at + parameter_block_bytes(1, 2))};
}

FrameParameters golden_parameters() {
  FrameParameters p;
  p.resize(1, 2);
  for (int i = 0; i < 27; ++i) p.parts[0].quadratic[i] = static_cast<float>(i);
  p.parts[0].rotation = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  p.parts[0].translation = {-10.0f, 20.0f, 30.5f};
  p.parts[0].rbf = true;
  p.weights = {0.5f, -0.25f, 1.0f, 2.0f, 3.0f, -4.0f};
  return p;
}

TEST(FrameParameters, MatchesGoldenBytesBothWaysWithoutAllocating) {
  const std::vector<unsigned char> golden = golden_block();
  const FrameParameters parameters = golden_parameters();
  std::vector<unsigned char> out(parameter_block_bytes(1, 2));
  FrameParameters decoded;
  decoded.resize(1, 2);
  {
    test::CountAllocations count;
    encode_parameter_block(parameters, out);
    decode_parameter_block(golden, decoded);
    EXPECT_EQ(count.count(), 0u);
  }
  EXPECT_EQ(out, golden);
  EXPECT_EQ(decoded.parts[0].quadratic, parameters.parts[0].quadratic);
  EXPECT_EQ(decoded.parts[0].translation, parameters.parts[0].translation);
  EXPECT_TRUE(decoded.parts[0].rbf);
  EXPECT_EQ(decoded.weights, parameters.weights);
}

TEST(FrameParameters, BlocksThatDoNotFitTheModelAreRejected) {
  const std::vector<unsigned char> golden = golden_block();
  FrameParameters other_model;
  other_model.resize(2, 2);
  EXPECT_THROW(decode_parameter_block(golden, other_model), DecodeError);
  FrameParameters fits;
  fits.resize(1, 2);
  for (size_t n = 0; n < golden.size(); ++n)
    EXPECT_THROW(decode_parameter_block(std::span(golden).first(n), fits), DecodeError) << n;
  std::vector<unsigned char> bad = golden;
  const float nan = std::nanf("");
  std::memcpy(bad.data() + 8 + 4 * 30, &nan, 4);  // a rotation entry
  EXPECT_THROW(decode_parameter_block(bad, fits), DecodeError);
  bad = golden;
  std::memcpy(bad.data() + bad.size() - 4, &nan, 4);  // a weight
  EXPECT_THROW(decode_parameter_block(bad, fits), DecodeError);
  bad = golden;
  bad[8 + 156] = 2;  // reserved flag bit
  EXPECT_THROW(decode_parameter_block(bad, fits), DecodeError);
}

// Found by fuzzing (tests/fuzz/frame_parameters_fuzz.cpp): the block of a model with no parts and
// no members (8 zero bytes) copied its weights with memcpy from an empty vector's null data()
// (undefined behaviour, reported by UBSan). It decodes to nothing, and encodes back the same.
TEST(FrameParameters, NoPartsAndNoMembersDecodeAndEncode) {
  std::ifstream in(test::source_path("tests/protocol/fixtures/fuzz/frame_parameters_no_parts_no_members.bin"), std::ios::binary);
  const std::vector<unsigned char> block{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  ASSERT_EQ(block, std::vector<unsigned char>(8, 0));
  FrameParameters none;
  decode_parameter_block(block, none);
  EXPECT_TRUE(none.parts.empty());
  EXPECT_TRUE(none.weights.empty());
  std::vector<unsigned char> again(parameter_block_bytes(0, 0), 0xff);
  encode_parameter_block(none, again);
  EXPECT_EQ(again, block);
}

}  // namespace
}  // namespace skinstream::subscriber
