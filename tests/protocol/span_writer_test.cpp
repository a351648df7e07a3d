// SpanWriter: values and arrays written in place, little-endian, without allocating.
#include "protocol/span_writer.h"

#include <gtest/gtest.h>

#include <array>
#include <vector>

#include "protocol/byte_reader.h"
#include "support/allocation_counter.h"

namespace skinstream {
namespace {

TEST(SpanWriter, WritesWhatTheReaderReads) {
  std::array<unsigned char, 4 + 2 + 8 + 3 + 1> out{};
  size_t allocations = 0;
  {
    test::CountAllocations counted;
    SpanWriter w(out);
    w.put<uint32_t>(0x01020304);
    w.put<uint16_t>(7);
    const float pair[2] = {1.5f, -2.0f};
    w.put_array<float>(pair);
    std::vector<float> none;
    w.put_array<float>(none);  // no values from no storage
    unsigned char* at = w.reserve(3);
    at[0] = 'a', at[1] = 'b', at[2] = 'c';
    w.zeros(1);
    EXPECT_EQ(w.position(), out.size());
    allocations = counted.count();
  }
  EXPECT_EQ(allocations, 0u);
  EXPECT_EQ(out[0], 4);
  ByteReader r(out);
  EXPECT_EQ(r.get<uint32_t>("word"), 0x01020304u);
  EXPECT_EQ(r.get<uint16_t>("half"), 7);
  EXPECT_EQ(r.get<float>("first"), 1.5f);
  EXPECT_EQ(r.get<float>("second"), -2.0f);
  EXPECT_EQ(r.get<uint8_t>("letter"), 'a');
  r.skip(2, "letters");
  EXPECT_EQ(r.get<uint8_t>("zero"), 0);
  EXPECT_TRUE(r.ok());
  EXPECT_EQ(r.remaining(), 0u);
}

}  // namespace
}  // namespace skinstream
