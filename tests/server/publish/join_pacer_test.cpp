#include "server/publish/join_pacer.h"

#include <gtest/gtest.h>

namespace skinstream::server {
namespace {

using namespace std::chrono_literals;

constexpr double kMegabytePerSecond = 1e6;

TEST(JoinPacer, AJoinerOnAQuietStageGoesAtOnce) {
  JoinPacer pacer(kMegabytePerSecond, 100'000);
  const auto now = JoinPacer::Clock::now();
  EXPECT_EQ(pacer.reserve(100'000, now), 0ns);
  EXPECT_EQ(pacer.totals().delayed, 0u);
}

TEST(JoinPacer, JoinersTogetherAreSpreadAtTheRate) {
  JoinPacer pacer(kMegabytePerSecond, 100'000);
  const auto now = JoinPacer::Clock::now();
  // Ten 100 kB pieces at 1 MB/s: the first within the burst, each next one 0.1 s later.
  for (int k = 0; k < 10; ++k) {
    const auto wait = pacer.reserve(100'000, now);
    EXPECT_NEAR(std::chrono::duration<double>(wait).count(), 0.1 * k, 1e-6) << k;
  }
  const JoinPacer::Totals totals = pacer.totals();
  EXPECT_EQ(totals.bytes, 1'000'000u);
  EXPECT_EQ(totals.delayed, 9u);
  EXPECT_NEAR(totals.waited_seconds, 0.1 * (1 + 9) * 9 / 2, 1e-5);
}

TEST(JoinPacer, IdleTimeGivesBackNoMoreThanTheBurst) {
  JoinPacer pacer(kMegabytePerSecond, 100'000);
  const auto start = JoinPacer::Clock::now();
  EXPECT_EQ(pacer.reserve(500'000, start), 400ms);  // half a second of bytes: 0.4 s beyond the burst
  // A minute later the link is long free, but only a burst goes at once.
  const auto later = start + 60s;
  EXPECT_EQ(pacer.reserve(100'000, later), 0ns);
  EXPECT_EQ(pacer.reserve(100'000, later), 100ms);
}

TEST(JoinPacer, WaitingOutTheDelayKeepsTheRate) {
  // A sender that waits what it was told and reserves again never goes faster than the rate.
  JoinPacer pacer(kMegabytePerSecond, 64'000);
  auto now = JoinPacer::Clock::now();
  const auto start = now;
  size_t sent = 0;
  for (int k = 0; k < 100; ++k) {
    now += pacer.reserve(64'000, now);
    sent += 64'000;
    const double elapsed = std::chrono::duration<double>(now - start).count();
    EXPECT_LE(static_cast<double>(sent), kMegabytePerSecond * elapsed + 64'000 + 1) << k;
  }
  EXPECT_NEAR(std::chrono::duration<double>(now - start).count(), 99 * 0.064, 1e-3);
}

}  // namespace
}  // namespace skinstream::server
