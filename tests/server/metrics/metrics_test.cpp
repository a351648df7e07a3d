// /metrics as Prometheus reads it: cumulative histogram buckets with an upper bound that
// includes its value, +Inf, sum and count; counters by category; label values escaped.
#include "server/metrics/metrics.h"

#include <gtest/gtest.h>

#include <map>
#include <sstream>
#include <string>

namespace skinstream::server {
namespace {

// The value of the first line starting with `prefix`, or -1 when there is none.
double value_of(const std::string& text, const std::string& prefix) {
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);)
    if (line.rfind(prefix, 0) == 0) return std::stod(line.substr(prefix.size()));
  return -1;
}

TEST(LatencyHistogram, BucketsAreCumulativeAndIncludeTheirBound) {
  LatencyHistogram h;
  h.observe_ns(900'000);     // 0.9 ms: in le=0.001, not in le=0.00075
  h.observe_ns(1'000'000);   // exactly 1 ms: in le=0.001
  h.observe_ns(1'900'000);   // 1.9 ms: in le=0.002, not in le=0.0015
  h.observe_ns(2'000'000'000);  // 2 s: beyond every bound, only in +Inf
  std::string out;
  h.render(out, "stage_seconds", "A stage.");
  EXPECT_NE(out.find("# TYPE skinstream_stage_seconds histogram\n"), std::string::npos) << out;
  EXPECT_EQ(value_of(out, "skinstream_stage_seconds_bucket{le=\"0.00075\"} "), 0);
  EXPECT_EQ(value_of(out, "skinstream_stage_seconds_bucket{le=\"0.001\"} "), 2);
  EXPECT_EQ(value_of(out, "skinstream_stage_seconds_bucket{le=\"0.0015\"} "), 2);
  EXPECT_EQ(value_of(out, "skinstream_stage_seconds_bucket{le=\"0.002\"} "), 3);
  EXPECT_EQ(value_of(out, "skinstream_stage_seconds_bucket{le=\"1\"} "), 3);
  EXPECT_EQ(value_of(out, "skinstream_stage_seconds_bucket{le=\"+Inf\"} "), 4);
  EXPECT_EQ(value_of(out, "skinstream_stage_seconds_count "), 4);
  EXPECT_NEAR(value_of(out, "skinstream_stage_seconds_sum "), 2.0038, 1e-9);
  EXPECT_EQ(h.count(), 4u);
}

TEST(LatencyHistogram, BoundsAscendAndEveryOneIsRendered) {
  for (size_t b = 1; b < LatencyHistogram::kBounds.size(); ++b)
    EXPECT_LT(LatencyHistogram::kBounds[b - 1], LatencyHistogram::kBounds[b]) << b;
  LatencyHistogram h;
  std::string out;
  h.render(out, "empty_seconds", "Nothing yet.");
  size_t buckets = 0;
  for (size_t at = out.find("_bucket{"); at != std::string::npos; at = out.find("_bucket{", at + 1)) ++buckets;
  EXPECT_EQ(buckets, LatencyHistogram::kBounds.size() + 1);  // and +Inf
}

TEST(LatencyHistogram, SummaryGivesEachQuantileAsItsBucketsBoundCappedByTheMaximum) {
  LatencyHistogram h;
  EXPECT_EQ(h.summary().count, 0u);
  EXPECT_EQ(h.summary().max_ms, 0.0);
  for (int i = 0; i < 98; ++i) h.observe_ns(400'000);  // 0.4 ms: bucket (0.3, 0.5] ms
  h.observe_ns(1'900'000);                              // 1.9 ms: bucket (1.5, 2] ms
  h.observe_ns(1'200'000);                              // 1.2 ms: bucket (1, 1.25] ms
  LatencyHistogram::Summary s = h.summary();
  EXPECT_EQ(s.count, 100u);
  EXPECT_DOUBLE_EQ(s.p50_le_ms, 0.5);
  EXPECT_DOUBLE_EQ(s.p99_le_ms, 1.25);  // the 99th of 100 values is 1.2 ms
  EXPECT_DOUBLE_EQ(s.p99_9_le_ms, 1.9);  // the 100th: its bucket says <= 2 ms, the maximum 1.9
  EXPECT_DOUBLE_EQ(s.max_ms, 1.9);
  // Beyond the last bound (1 s) a quantile is bounded by the maximum alone.
  for (int i = 0; i < 900; ++i) h.observe_ns(3'000'000'000);
  s = h.summary();
  EXPECT_DOUBLE_EQ(s.p50_le_ms, 3000.0);
  EXPECT_DOUBLE_EQ(s.max_ms, 3000.0);
}

// The quantile over any bucket counts (an interval's, for the status line): the bound of the
// bucket holding the nearest-rank observation, or the caller's figure past the last bucket.
TEST(LatencyHistogram, QuantileOverBucketCountsIsItsBucketsBound) {
  LatencyHistogram::Buckets counts{};
  counts[6] = 98;  // (0.3, 0.5] ms
  counts[17] = 2;  // (7.5, 10] ms
  EXPECT_DOUBLE_EQ(LatencyHistogram::quantile_upper_bound_ms(counts, 100, 0.5, -1.0), 0.5);
  EXPECT_DOUBLE_EQ(LatencyHistogram::quantile_upper_bound_ms(counts, 100, 0.98, -1.0), 0.5);
  EXPECT_DOUBLE_EQ(LatencyHistogram::quantile_upper_bound_ms(counts, 100, 0.99, -1.0), 10.0);
  // Two more observations beyond the last bound: the 101st of 102 is one of them.
  EXPECT_DOUBLE_EQ(LatencyHistogram::quantile_upper_bound_ms(counts, 102, 0.99, 3000.0), 3000.0);
  EXPECT_DOUBLE_EQ(LatencyHistogram::quantile_upper_bound_ms(counts, 102, 0.98, 3000.0), 10.0);
}

TEST(Metrics, BadInputIsCountedByCategoryAndLabelValuesAreEscaped) {
  Metrics source;
  source.count_bad_input("nan");
  source.count_bad_input("nan");
  source.count_bad_input("wrong_marker_count");
  source.frames_received = 7;
  EXPECT_EQ(source.bad_input("nan"), 2u);
  EXPECT_EQ(source.bad_input("unseen"), 0u);
  Metrics subject;
  subject.frames_received = 5;
  SubscriberMetrics s;
  s.id = 3;
  s.transport = "tcp";
  s.remote = "a\"b\\c\nd";
  s.sent = 11;
  const std::string out = render_prometheus(source, {{"A\"1", &subject, {s}}});
  EXPECT_EQ(value_of(out, "skinstream_source_frames_total "), 7);
  EXPECT_EQ(value_of(out, "skinstream_frames_received_total{subject=\"A\\\"1\"} "), 5);
  EXPECT_EQ(value_of(out, "skinstream_bad_input_total{category=\"nan\"} "), 2);
  EXPECT_EQ(value_of(out, "skinstream_bad_input_total{category=\"wrong_marker_count\"} "), 1);
  EXPECT_EQ(value_of(out, "skinstream_subscriber_frames_sent_total{subject=\"A\\\"1\",id=\"3\",transport=\"tcp\",remote=\"a\\\"b\\\\c\\nd\"} "), 11);
  EXPECT_EQ(value_of(out, "skinstream_subscribers{subject=\"A\\\"1\"} "), 1);
}

// Several subjects: each metric's HELP and TYPE once, then a sample per subject, labelled.
TEST(Metrics, EverySubjectHasItsOwnLabelledSeriesUnderOneHeader) {
  Metrics source, actor1, actor2;
  actor1.frames_published = 100;
  actor2.frames_published = 200;
  actor1.fill.observe_ns(400'000);
  actor2.fill.observe_ns(400'000);
  actor2.fill.observe_ns(400'000);
  actor2.count_bad_input("deform_failed");
  const std::string out = render_prometheus(source, {{"Actor1", &actor1, {}}, {"Actor2", &actor2, {}}});
  EXPECT_EQ(value_of(out, "skinstream_frames_published_total{subject=\"Actor1\"} "), 100);
  EXPECT_EQ(value_of(out, "skinstream_frames_published_total{subject=\"Actor2\"} "), 200);
  EXPECT_EQ(value_of(out, "skinstream_fill_seconds_count{subject=\"Actor1\"} "), 1);
  EXPECT_EQ(value_of(out, "skinstream_fill_seconds_bucket{subject=\"Actor2\",le=\"0.0005\"} "), 2);
  EXPECT_EQ(value_of(out, "skinstream_bad_input_total{subject=\"Actor2\",category=\"deform_failed\"} "), 1);
  EXPECT_EQ(value_of(out, "skinstream_subscribers{subject=\"Actor2\"} "), 0);
  std::istringstream lines(out);
  std::map<std::string, int> types;
  for (std::string line; std::getline(lines, line);)
    if (line.rfind("# TYPE ", 0) == 0) ++types[line.substr(7, line.find(' ', 7) - 7)];
  EXPECT_GT(types.size(), 20u);
  for (const auto& [name, count] : types) EXPECT_EQ(count, 1) << name;
}

}  // namespace
}  // namespace skinstream::server
