// ByteWriter at its edges: nothing to write from no storage, strings.
#include "protocol/byte_buffer.h"

#include <gtest/gtest.h>

#include <vector>

namespace skinstream {
namespace {

// An empty vector's data() is null: writing no values through it must not hand memcpy a null
// pointer (undefined even for 0 bytes; the sanitizer build, scripts/sanitize.sh, stops on it).
TEST(ByteBuffer, NoValuesFromNoStorage) {
  std::vector<float> none;
  ASSERT_EQ(none.data(), nullptr);
  ByteWriter writer;
  writer.put_bytes(none.data(), 0);
  EXPECT_TRUE(writer.bytes().empty());
}

TEST(ByteBuffer, StringsAreALengthAndTheirBytes) {
  ByteWriter writer;
  writer.put_string("ab");
  EXPECT_EQ(writer.bytes(), (std::vector<unsigned char>{2, 0, 0, 0, 'a', 'b'}));
}

}  // namespace
}  // namespace skinstream
