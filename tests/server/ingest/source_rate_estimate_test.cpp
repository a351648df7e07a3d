// The NatNet source's rate from the frames' own timestamps: exact under a capture clock's jitter
// and quantisation, a real change of rate taken once, restarts and garbage survived.
#include "server/ingest/source_rate_estimate.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>
#include <vector>

namespace skinstream::server {
namespace {

// Every rate the estimate reported over `frames` frames of a `hz` stream whose timestamps are
// `stamp(k)`, from the first it reported on.
template <typename Stamp>
std::set<double> rates_over(SourceRateEstimate& estimate, int64_t first, int frames, Stamp stamp) {
  std::set<double> seen;
  for (int k = 0; k < frames; ++k) {
    const double hz = estimate.add(first + k, stamp(k));
    if (hz > 0.0) seen.insert(hz);
  }
  return seen;
}

TEST(SourceRateEstimate, ClockJitterNeverChangesTheRate) {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> jitter(-20e-6, 20e-6);
  SourceRateEstimate estimate;
  const std::set<double> seen = rates_over(estimate, 1, 120 * 600, [&](int k) { return 100.0 + k / 120.0 + jitter(random); });
  EXPECT_EQ(seen, std::set<double>{120.0});
}

TEST(SourceRateEstimate, ATenMegahertzClockGivesTheExactRate) {
  SourceRateEstimate estimate;
  const std::set<double> seen =
      rates_over(estimate, 1, 120 * 600, [](int k) { return static_cast<double>(std::llround(k * 1e7 / 120.0)) / 1e7; });
  EXPECT_EQ(seen, std::set<double>{120.0});
  SourceRateEstimate odd;  // a rate that is no whole number, on the same clock
  const std::set<double> odd_seen =
      rates_over(odd, 1, 120 * 600, [](int k) { return static_cast<double>(std::llround(k * 1e7 * 1.001 / 120.0)) / 1e7; });
  ASSERT_EQ(odd_seen.size(), 1u);
  EXPECT_NEAR(*odd_seen.begin(), 119.88, 0.005);
}

TEST(SourceRateEstimate, KnownAfterHalfASecond) {
  SourceRateEstimate estimate;
  for (int k = 0; k < 60; ++k) EXPECT_EQ(estimate.add(k, k / 120.0), 0.0) << k;
  EXPECT_EQ(estimate.add(60, 60 / 120.0), 120.0);
}

// The first estimate, of half a second, is provisional: the first whole window's replaces it,
// however close (a clock 0.05% fast that stepped 200 us as the first window closed, which made
// the first estimate look like 120 Hz).
TEST(SourceRateEstimate, TheFirstWholeWindowReplacesTheProvisionalRate) {
  SourceRateEstimate estimate;
  std::vector<double> rates;
  double last = 0.0;
  for (int k = 0; k < 1200; ++k) {
    const double jitter = k >= 60 ? 200e-6 : 0.0;
    const double now = estimate.add(k, k / 120.06 + jitter);
    if (now != last) rates.push_back(now);
    last = now;
  }
  ASSERT_EQ(rates.size(), 2u);
  EXPECT_EQ(rates.back(), 120.06);
}

TEST(SourceRateEstimate, ARealChangeOfRateIsTakenOnce) {
  SourceRateEstimate estimate;
  int64_t number = 0;
  double t = 0.0;
  std::vector<double> changes;
  double last = 0.0;
  auto run = [&](double hz, int frames) {
    for (int k = 0; k < frames; ++k, ++number, t += 1.0 / hz) {
      const double now = estimate.add(number, t);
      if (now != last) changes.push_back(now);
      last = now;
    }
  };
  run(120.0, 1200);
  run(240.0, 2400);
  EXPECT_EQ(changes, (std::vector<double>{120.0, 240.0}));
}

TEST(SourceRateEstimate, LoopsRestartsAndPausesKeepTheRate) {
  SourceRateEstimate estimate;
  for (int loop = 0; loop < 5; ++loop)
    for (int k = 0; k < 90; ++k) estimate.add(100 + k, k / 120.0);  // three quarters of a second, then back to its start
  EXPECT_EQ(estimate.rate_hz(), 120.0);
  for (int k = 0; k < 10; ++k) estimate.add(200 + k, 50.0 + k / 120.0);  // a pause of 50 s
  EXPECT_EQ(estimate.rate_hz(), 120.0);
  estimate.reset();
  EXPECT_EQ(estimate.rate_hz(), 0.0);
}

TEST(SourceRateEstimate, GarbageTimestampsChangeTheRateRarely) {
  std::mt19937 random(3);
  std::uniform_real_distribution<double> step(1e-6, 0.1);
  SourceRateEstimate estimate;
  double t = 0.0, last = 0.0;
  int changes = 0;
  for (int k = 0; k < 120 * 60; ++k) {
    t += step(random);
    const double now = estimate.add(k, k % 97 == 0 ? std::nan("") : t);
    EXPECT_TRUE(now == 0.0 || (now > 0.0 && now <= SourceRateEstimate::kMaxRateHz)) << now;
    changes += now != last;
    last = now;
  }
  // At most one change per two windows of the source's clock.
  EXPECT_LE(changes, static_cast<int>(t / (2 * SourceRateEstimate::kWindowSeconds)) + 1);
}

}  // namespace
}  // namespace skinstream::server
