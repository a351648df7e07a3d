// ByteReader and ByteWriter at their edges: nothing to read into no storage, bounds, strings.
#include "protocol/byte_buffer.h"

#include <gtest/gtest.h>

#include <vector>

namespace skinstream {
namespace {

// An empty vector's data() is null: reading or writing no values through it must not hand memcpy
// a null pointer (undefined even for 0 bytes; the sanitizer build, scripts/sanitize.sh, stops on
// it). Found by fuzzing decode_frame with V = 0.
TEST(ByteBuffer, NoValuesIntoOrFromNoStorage) {
  std::vector<float> none;
  ASSERT_EQ(none.data(), nullptr);
  const unsigned char bytes[] = {1, 2, 3, 4};
  ByteReader reader(bytes, sizeof bytes);
  reader.get_array(none.data(), 0);
  EXPECT_EQ(reader.position(), 0u);
  ByteReader empty(nullptr, 0);
  empty.get_array(none.data(), 0);
  EXPECT_EQ(empty.remaining(), 0u);
  ByteWriter writer;
  writer.put_bytes(none.data(), 0);
  EXPECT_TRUE(writer.bytes().empty());
}

TEST(ByteBuffer, ReadsPastTheEndThrow) {
  const unsigned char bytes[] = {1, 0, 0, 0, 9};
  ByteReader reader(bytes, sizeof bytes);
  EXPECT_EQ(reader.get<uint32_t>(), 1u);
  float two[2];
  EXPECT_THROW(reader.get_array(two, 2), std::out_of_range);
  EXPECT_THROW(reader.get<uint32_t>(), std::out_of_range);
  EXPECT_EQ(reader.get<uint8_t>(), 9);
}

}  // namespace
}  // namespace skinstream
