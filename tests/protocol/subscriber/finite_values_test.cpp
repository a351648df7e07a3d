// all_finite: every kind of float that is not finite is found wherever it sits in the buffer; the
// largest finite values, subnormals and negative zero are finite.
#include "protocol/subscriber/finite_values.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

namespace skinstream {
namespace {

TEST(FiniteValues, FindsEveryNonFiniteValueAnywhere) {
  const float bad[] = {std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity(),
                       std::numeric_limits<float>::quiet_NaN(), -std::numeric_limits<float>::quiet_NaN(),
                       std::numeric_limits<float>::signaling_NaN()};
  for (const size_t size : {1, 3, 4, 5, 7, 8, 1001}) {
    std::vector<float> values(size, 1.0f);
    EXPECT_TRUE(all_finite(values));
    for (size_t at = 0; at < size; ++at)
      for (float b : bad) {
        values[at] = b;
        EXPECT_FALSE(all_finite(values)) << "size " << size << " at " << at << " value " << b;
        values[at] = 1.0f;
      }
  }
  EXPECT_TRUE(all_finite({}));
}

TEST(FiniteValues, ExtremeFiniteValuesAreFinite) {
  const std::vector<float> values = {std::numeric_limits<float>::max(), std::numeric_limits<float>::lowest(),
                                     std::numeric_limits<float>::denorm_min(), std::numeric_limits<float>::min(), -0.0f, 0.0f,
                                     3.4e38f};
  EXPECT_TRUE(all_finite(values));
}

}  // namespace
}  // namespace skinstream
