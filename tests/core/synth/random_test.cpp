#include "core/synth/random.h"

#include <gtest/gtest.h>

#include <cmath>

namespace skinstream::synth {
namespace {

TEST(SynthRandom, DegenerateArgumentsAreSafe) {
  Random r(1);
  EXPECT_EQ(r.below(0), 0);
  EXPECT_EQ(r.below(1), 0);
  EXPECT_EQ(r.poisson(0.0), 0);
  EXPECT_EQ(r.poisson(-3.0), 0);
  EXPECT_EQ(r.geometric(0.5), 1);
  EXPECT_FALSE(r.chance(0.0));
  EXPECT_TRUE(r.chance(1.0));
}

TEST(SynthRandom, SameSeedSameNumbersOtherSeedOthers) {
  Random a(42), b(42), c(43);
  bool differ = false;
  for (int i = 0; i < 100; ++i) {
    const double x = a.normal(), y = b.normal(), z = c.normal();
    EXPECT_EQ(x, y);
    differ |= x != z;
  }
  EXPECT_TRUE(differ);
}

TEST(SynthRandom, StreamsAreIndependentOfEachOther) {
  Random a = Random::stream(7, 1), b = Random::stream(7, 2), a2 = Random::stream(7, 1);
  for (int i = 0; i < 10; ++i) {
    const uint64_t x = a.bits();
    EXPECT_EQ(x, a2.bits());
    EXPECT_NE(x, b.bits());
  }
}

TEST(SynthRandom, DistributionsHaveTheirMoments) {
  Random r(2024);
  const int n = 200000;
  double sum = 0, sum2 = 0, u_sum = 0, e_sum = 0, p_sum = 0, g_sum = 0;
  int below_hits[5] = {0, 0, 0, 0, 0};
  for (int i = 0; i < n; ++i) {
    const double x = r.normal();
    sum += x;
    sum2 += x * x;
    const double u = r.uniform();
    ASSERT_GE(u, 0.0);
    ASSERT_LT(u, 1.0);
    u_sum += u;
    e_sum += r.exponential(2.0);
    p_sum += r.poisson(3.5);
    g_sum += r.geometric(4.0);
    const int k = r.below(5);
    ASSERT_GE(k, 0);
    ASSERT_LT(k, 5);
    ++below_hits[k];
  }
  EXPECT_NEAR(sum / n, 0.0, 0.01);
  EXPECT_NEAR(sum2 / n, 1.0, 0.02);
  EXPECT_NEAR(u_sum / n, 0.5, 0.005);
  EXPECT_NEAR(e_sum / n, 2.0, 0.03);
  EXPECT_NEAR(p_sum / n, 3.5, 0.03);
  EXPECT_NEAR(g_sum / n, 4.0, 0.05);
  for (int h : below_hits) EXPECT_NEAR(h / static_cast<double>(n), 0.2, 0.005);
}

}  // namespace
}  // namespace skinstream::synth
