#include "server/control/control_rate_limit.h"

#include <gtest/gtest.h>

#include <string>

namespace skinstream::server {
namespace {

using std::chrono::milliseconds;
using std::chrono::seconds;

const ControlRateLimitOptions kOptions{
    .max_refusals = 5, .window = seconds(10), .block = seconds(60), .max_addresses = 4};

TEST(ControlRateLimit, TheFifthWrongTokenWithinTheWindowBlocksThatAddressOnly) {
  ControlRateLimit limit(kOptions);
  const auto t0 = ControlRateLimit::Clock::now();
  for (int i = 0; i < 4; ++i) {
    EXPECT_FALSE(limit.count_refusal("10.0.0.5", t0 + seconds(i)));
    EXPECT_EQ(limit.blocked_for("10.0.0.5", t0 + seconds(i)), milliseconds(0));
  }
  EXPECT_TRUE(limit.count_refusal("10.0.0.5", t0 + seconds(4)));
  EXPECT_EQ(limit.blocked_for("10.0.0.5", t0 + seconds(4)), seconds(60));
  EXPECT_EQ(limit.blocked_for("10.0.0.5", t0 + seconds(50)), seconds(14));
  EXPECT_EQ(limit.blocked_for("10.0.0.6", t0 + seconds(5)), milliseconds(0));
  EXPECT_EQ(limit.blocked_for("10.0.0.5", t0 + seconds(64)), milliseconds(0));
}

TEST(ControlRateLimit, RefusalsSpreadBeyondTheWindowDoNotBlock) {
  ControlRateLimit limit(kOptions);
  const auto t0 = ControlRateLimit::Clock::now();
  for (int i = 0; i < 20; ++i) EXPECT_FALSE(limit.count_refusal("10.0.0.5", t0 + seconds(3 * i)));
  EXPECT_EQ(limit.blocked_for("10.0.0.5", t0 + seconds(60)), milliseconds(0));
}

TEST(ControlRateLimit, AFloodOfAddressesIsBoundedAndBlockedTogether) {
  ControlRateLimit limit(kOptions);
  const auto t0 = ControlRateLimit::Clock::now();
  for (int i = 0; i < 1000; ++i)
    limit.count_refusal("10.1." + std::to_string(i / 250) + "." + std::to_string(i % 250), t0);
  EXPECT_EQ(limit.tracked_addresses(), kOptions.max_addresses);
  // The addresses the table had no room for shared one entry, blocked after 5 of them.
  EXPECT_GT(limit.blocked_for("10.9.9.9", t0 + seconds(1)), milliseconds(0));
  // One address of the table, refused once, is not blocked.
  EXPECT_EQ(limit.blocked_for("10.1.0.0", t0 + seconds(1)), milliseconds(0));
}

TEST(ControlRateLimit, ExpiredEntriesMakeRoomForNewAddresses) {
  ControlRateLimit limit(kOptions);
  const auto t0 = ControlRateLimit::Clock::now();
  for (int i = 0; i < 4; ++i) limit.count_refusal("10.0.0." + std::to_string(i), t0);
  ASSERT_EQ(limit.tracked_addresses(), 4u);
  const auto later = t0 + seconds(11);
  for (int i = 0; i < 4; ++i) EXPECT_FALSE(limit.count_refusal("10.0.1.1", later + seconds(i)));
  EXPECT_TRUE(limit.count_refusal("10.0.1.1", later + seconds(4)));
  // Its own entry took the place of the expired ones: another address is not blocked with it.
  EXPECT_EQ(limit.tracked_addresses(), 1u);
  EXPECT_EQ(limit.blocked_for("10.0.2.2", later + seconds(5)), milliseconds(0));
}

}  // namespace
}  // namespace skinstream::server
