#include "clients/bench/stall_log.h"

#include <gtest/gtest.h>

namespace skinstream::bench {
namespace {

constexpr int64_t kSecond = 1'000'000'000;

TEST(StallLog, KeepsNothingBeforeTheStartOrBeforeTheMeasuredWindow) {
  StallLog log;
  log.add_gap(5 * kSecond, "replay", 40.0);  // not started: the warm-up
  log.start(10 * kSecond);
  log.add_gap(9 * kSecond, "subscriber 0", 30.0);  // began before the window
  EXPECT_TRUE(log.to_json()["events"].empty());
}

TEST(StallLog, ListsGapsAndDropsInTimeOrderFromTheStart) {
  StallLog log;
  log.start(10 * kSecond);
  log.add_drop(12 * kSecond + kSecond / 2, "subscriber 1", 3);
  log.add_gap(12 * kSecond, "replay", 46.5);
  log.add_gap(12 * kSecond + kSecond / 4, "subscriber 1", 52.0);
  const nlohmann::json j = log.to_json();
  ASSERT_EQ(j["events"].size(), 3u);
  EXPECT_EQ(j["events"][0]["who"], "replay");
  EXPECT_DOUBLE_EQ(j["events"][0]["at_s"].get<double>(), 2.0);
  EXPECT_DOUBLE_EQ(j["events"][0]["gap_ms"].get<double>(), 46.5);
  EXPECT_FALSE(j["events"][0].contains("dropped"));
  EXPECT_EQ(j["events"][1]["who"], "subscriber 1");
  EXPECT_DOUBLE_EQ(j["events"][1]["at_s"].get<double>(), 2.25);
  EXPECT_EQ(j["events"][2]["dropped"], 3);
  EXPECT_FALSE(j["events"][2].contains("gap_ms"));
  EXPECT_EQ(j["events_not_kept"], 0);
}

TEST(StallLog, CountsWhatDoesNotFit) {
  StallLog log(2);
  log.start(0);
  for (int i = 0; i < 5; ++i) log.add_gap(i * kSecond, "replay", 30.0);
  const nlohmann::json j = log.to_json();
  EXPECT_EQ(j["events"].size(), 2u);
  EXPECT_EQ(j["events_not_kept"], 3);
}

}  // namespace
}  // namespace skinstream::bench
