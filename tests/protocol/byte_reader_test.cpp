// ByteReader: reads past the end are values naming the field and the offset, the first failure
// sticks, nothing is read into no storage, and reading allocates nothing.
#include "protocol/byte_reader.h"

#include <gtest/gtest.h>

#include <array>
#include <vector>

#include "support/allocation_counter.h"

namespace skinstream {
namespace {

TEST(ByteReader, ReadsLittleEndianValuesInOrder) {
  const unsigned char bytes[] = {1, 0, 0, 0, 0x34, 0x12, 9};
  ByteReader r(bytes, sizeof bytes);
  EXPECT_EQ(r.get<uint32_t>("first"), 1u);
  EXPECT_EQ(r.get<uint16_t>("second"), 0x1234);
  uint8_t third = 0;
  EXPECT_TRUE(r.read(third, "third"));
  EXPECT_EQ(third, 9);
  EXPECT_TRUE(r.ok());
  EXPECT_EQ(r.position(), 7u);
  EXPECT_EQ(r.remaining(), 0u);
}

TEST(ByteReader, AReadPastTheEndNamesTheFieldAndTheOffset) {
  const unsigned char bytes[] = {1, 0, 0, 0, 9, 9};
  ByteReader r(bytes, sizeof bytes);
  EXPECT_EQ(r.get<uint32_t>("count"), 1u);
  EXPECT_EQ(r.get<uint32_t>("frame number"), 0u);
  ASSERT_FALSE(r.ok());
  const ByteError& e = r.error();
  EXPECT_TRUE(static_cast<bool>(e));
  EXPECT_STREQ(e.field, "frame number");
  EXPECT_EQ(e.offset, 4u);
  EXPECT_EQ(e.wanted, 4u);
  EXPECT_EQ(e.available, 2u);
  EXPECT_EQ(e.message(), "truncated in frame number: needs 4 bytes at offset 4, 2 left");
  EXPECT_EQ(r.position(), 4u);  // a failed read moves nothing
}

TEST(ByteReader, TheFirstFailureSticks) {
  const unsigned char bytes[] = {1, 2, 3, 4, 5};
  ByteReader r(bytes, sizeof bytes);
  float two[2] = {7, 7};
  EXPECT_FALSE(r.get_array(two, 2, "pair"));
  EXPECT_EQ(two[0], 7);  // untouched
  // Every later read fails and gives zero or empty, even one that would fit; the error stays the first.
  EXPECT_EQ(r.get<uint8_t>("one byte"), 0);
  uint16_t v = 5;
  EXPECT_FALSE(r.read(v, "another"));
  EXPECT_EQ(v, 5);
  EXPECT_TRUE(r.take(1, "a block").empty());
  EXPECT_FALSE(r.skip(1, "a gap"));
  EXPECT_EQ(r.get_count(1, "items"), 0u);
  EXPECT_STREQ(r.error().field, "pair");
  EXPECT_EQ(r.error().wanted, 8u);
  EXPECT_EQ(r.error().available, 5u);
  EXPECT_EQ(r.position(), 0u);
}

TEST(ByteReader, ACountMustFitInWhatIsLeft) {
  const unsigned char bytes[] = {3, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8};
  ByteReader fits(bytes, sizeof bytes);
  EXPECT_EQ(fits.get_count(2, "pairs"), 3u);
  EXPECT_TRUE(fits.ok());
  ByteReader too_many(bytes, sizeof bytes);
  EXPECT_EQ(too_many.get_count(4, "quads"), 0u);
  ASSERT_FALSE(too_many.ok());
  EXPECT_STREQ(too_many.error().field, "quads");
  EXPECT_EQ(too_many.error().offset, 4u);  // after the count
  EXPECT_EQ(too_many.error().wanted, 12u);
  EXPECT_EQ(too_many.error().available, 8u);
}

TEST(ByteReader, TakesBlocksInPlaceAndFailsWithoutMoving) {
  const unsigned char bytes[] = {1, 2, 3, 4, 5};
  ByteReader r{std::span<const unsigned char>(bytes)};
  const std::span<const unsigned char> block = r.take(3, "block");
  EXPECT_EQ(block.data(), bytes);
  EXPECT_EQ(block.size(), 3u);
  ByteReader peek = r;  // a copy reads ahead without moving the original
  EXPECT_EQ(peek.get<uint8_t>("next"), 4);
  EXPECT_EQ(r.position(), 3u);
  EXPECT_TRUE(r.take(3, "rest").empty());
  EXPECT_EQ(r.error().offset, 3u);
  EXPECT_EQ(r.error().available, 2u);
}

// An empty vector's data() is null: reading no values into it must not hand memcpy a null
// pointer (undefined even for 0 bytes; the sanitizer build, scripts/sanitize.sh, stops on it).
// Found by fuzzing decode_frame with V = 0.
TEST(ByteReader, NoValuesIntoNoStorage) {
  std::vector<float> none;
  ASSERT_EQ(none.data(), nullptr);
  const unsigned char bytes[] = {1, 2, 3, 4};
  ByteReader reader(bytes, sizeof bytes);
  EXPECT_TRUE(reader.get_array(none.data(), 0, "nothing"));
  EXPECT_EQ(reader.position(), 0u);
  ByteReader empty(nullptr, 0);
  EXPECT_TRUE(empty.get_array(none.data(), 0, "nothing"));
  EXPECT_TRUE(empty.take(0, "nothing").empty());
  EXPECT_TRUE(empty.ok());
  EXPECT_EQ(empty.get<uint8_t>("a byte"), 0);
  EXPECT_FALSE(empty.ok());
}

// The per-frame readers (Vicon, QTM, NatNet, the subscriber codecs) read every frame with it.
TEST(ByteReader, ReadingAllocatesNothingNorDoesFailing) {
  std::array<unsigned char, 64> bytes{};
  bytes[0] = 2;
  size_t allocations = 0;
  {
    test::CountAllocations counted;
    ByteReader r(bytes);
    const uint32_t n = r.get_count(8, "pairs");
    std::array<float, 4> values{};
    r.get_array(values.data(), 2 * n, "pairs");
    r.skip(4, "gap");
    const auto block = r.take(8, "block");
    r.get<double>("value");
    r.get<uint64_t>("past the end");
    r.get<uint8_t>("after the failure");
    allocations = counted.count();
    EXPECT_EQ(block.size(), 8u);
  }
  EXPECT_EQ(allocations, 0u);
}

}  // namespace
}  // namespace skinstream
