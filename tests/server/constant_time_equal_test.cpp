#include "server/constant_time_equal.h"

#include <gtest/gtest.h>

#include <string>

namespace skinstream::server {
namespace {

TEST(ConstantTimeEqual, DifferentLengthsNeverMatch) {
  EXPECT_FALSE(constant_time_equal("secret-token", "secret-token-and-more"));
  EXPECT_FALSE(constant_time_equal("secret-token-and-more", "secret-token"));
  EXPECT_FALSE(constant_time_equal("", "x"));
  // Shorter input padded with zero bytes must still differ from one that ends in zero bytes.
  EXPECT_FALSE(constant_time_equal(std::string("ab"), std::string("ab\0", 3)));
  EXPECT_FALSE(constant_time_equal(std::string("ab\0\0", 4), std::string("ab")));
}

TEST(ConstantTimeEqual, ADifferenceAnywhereIsFound) {
  const std::string token = "0123456789abcdef0123456789abcdef";
  for (size_t i = 0; i < token.size(); ++i) {
    for (const unsigned char flip : {0x01, 0x80, 0xff}) {
      std::string other = token;
      other[i] = static_cast<char>(static_cast<unsigned char>(other[i]) ^ flip);
      EXPECT_FALSE(constant_time_equal(token, other)) << "byte " << i << " flipped by " << int(flip);
    }
  }
}

TEST(ConstantTimeEqual, EqualStringsMatch) {
  EXPECT_TRUE(constant_time_equal("", ""));
  EXPECT_TRUE(constant_time_equal("0123456789abcdef", std::string("0123456789abcdef")));
  const std::string binary("\0\xff\x80 z", 5);
  EXPECT_TRUE(constant_time_equal(binary, std::string(binary)));
}

}  // namespace
}  // namespace skinstream::server
