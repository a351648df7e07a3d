// A running count's rate between samples, as /health and the status line read frames/s.
#include "server/metrics/rate_sampler.h"

#include <gtest/gtest.h>

namespace skinstream::server {
namespace {

TEST(RateSampler, EachSampleCoversTheIntervalSinceThePreviousOne) {
  const auto start = RateSampler::Clock::now();
  RateSampler rate(start);
  EXPECT_DOUBLE_EQ(rate.seconds_since_sample(start + std::chrono::milliseconds(250)), 0.25);

  RateSampler::Interval first = rate.sample(240, start + std::chrono::seconds(2));
  EXPECT_EQ(first.count, 240u);
  EXPECT_DOUBLE_EQ(first.seconds, 2.0);
  EXPECT_DOUBLE_EQ(first.per_second(), 120.0);

  // The next interval starts where the first ended, not at the start.
  RateSampler::Interval second = rate.sample(540, start + std::chrono::seconds(7));
  EXPECT_EQ(second.count, 300u);
  EXPECT_DOUBLE_EQ(second.seconds, 5.0);
  EXPECT_DOUBLE_EQ(second.per_second(), 60.0);
  EXPECT_DOUBLE_EQ(rate.seconds_since_sample(start + std::chrono::seconds(8)), 1.0);

  // No time between two samples: no rate rather than a division by zero.
  EXPECT_EQ(rate.sample(600, start + std::chrono::seconds(7)).per_second(), 0.0);
}

}  // namespace
}  // namespace skinstream::server
