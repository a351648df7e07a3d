#include "server/http/query_parameter.h"

#include <gtest/gtest.h>

namespace skinstream::server {
namespace {

TEST(QueryParameter, AbsentOrMalformedIsNone) {
  EXPECT_FALSE(query_parameter("/stream", "token"));
  EXPECT_FALSE(query_parameter("/stream?tokens=a", "token"));
  EXPECT_FALSE(query_parameter("/stream?token=a%2", "token"));
  EXPECT_FALSE(query_parameter("/stream?token=a%zz", "token"));
}

TEST(QueryParameter, FindsTheNamedParameterAndDecodesEscapes) {
  EXPECT_EQ(query_parameter("/stream?token=stage-7%2Feast", "token"), "stage-7/east");
  EXPECT_EQ(query_parameter("/stream?x=1&token=a%20b&y=2", "token"), "a b");
  EXPECT_EQ(query_parameter("/stream?token=", "token"), "");
  EXPECT_EQ(query_parameter("/stream?token", "token"), "");
  EXPECT_EQ(query_parameter("/stream?token=abc#fragment", "token"), "abc");
}

}  // namespace
}  // namespace skinstream::server
