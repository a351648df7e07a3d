#include "core/evaluation/error_stats.h"

#include <gtest/gtest.h>

namespace skinstream {
namespace {

TEST(FillErrorStats, EmptyInputGivesZeroCountAndZeros) {
  const ErrorStats stats = summarize_errors({});
  EXPECT_EQ(stats.count, 0);
  EXPECT_EQ(stats.mean, 0.0);
  EXPECT_EQ(stats.median, 0.0);
  EXPECT_EQ(stats.p95, 0.0);
  EXPECT_EQ(stats.max, 0.0);
}

TEST(FillErrorStats, OneValueIsEveryStatistic) {
  const ErrorStats stats = summarize_errors({2.5});
  EXPECT_EQ(stats.count, 1);
  EXPECT_EQ(stats.mean, 2.5);
  EXPECT_EQ(stats.median, 2.5);
  EXPECT_EQ(stats.p95, 2.5);
  EXPECT_EQ(stats.max, 2.5);
}

TEST(FillErrorStats, OddAndEvenMedians) {
  EXPECT_EQ(summarize_errors({5, 1, 3}).median, 3.0);
  EXPECT_EQ(summarize_errors({4, 1, 3, 2}).median, 2.5);
}

TEST(FillErrorStats, P95IsTheNearestRank) {
  std::vector<double> hundred;
  for (int i = 100; i >= 1; --i) hundred.push_back(i);
  EXPECT_EQ(summarize_errors(hundred).p95, 95.0);  // rank ceil(95) = 95
  std::vector<double> twenty;
  for (int i = 1; i <= 20; ++i) twenty.push_back(i);
  EXPECT_EQ(summarize_errors(twenty).p95, 19.0);          // rank ceil(19) = 19
  EXPECT_EQ(summarize_errors({1, 2, 3, 4, 5}).p95, 5.0);  // rank ceil(4.75) = 5
  std::vector<double> twenty_one(21, 0.0);
  twenty_one.back() = 7.0;
  // rank ceil(19.95) = 20: the 20th smallest is still 0 (an interpolating percentile would not be)
  EXPECT_EQ(summarize_errors(twenty_one).p95, 0.0);
}

TEST(FillErrorStats, MeanAndMax) {
  const ErrorStats stats = summarize_errors({1, 2, 3, 10});
  EXPECT_EQ(stats.count, 4);
  EXPECT_DOUBLE_EQ(stats.mean, 4.0);
  EXPECT_EQ(stats.max, 10.0);
}

}  // namespace
}  // namespace skinstream
