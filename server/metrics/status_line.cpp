#include "server/metrics/status_line.h"

#include <cstdio>

namespace skinstream::server {
namespace {

// The interval's p99 as its bucket's upper bound (ms); 0 without observations. Observations
// beyond the last bound are not in the buckets and not counted.
double p99_upper_bound_ms(const LatencyHistogram::Buckets& now, const LatencyHistogram::Buckets& before) {
  LatencyHistogram::Buckets interval;
  uint64_t total = 0;
  for (size_t b = 0; b < now.size(); ++b) {
    interval[b] = now[b] - before[b];
    total += interval[b];
  }
  return total == 0 ? 0.0 : LatencyHistogram::quantile_upper_bound_ms(interval, total, 0.99, LatencyHistogram::kBounds.back() * 1e3);
}

}  // namespace

std::string StatusLine::next(std::string_view subject, const Metrics& metrics, size_t subscribers, uint64_t subscriber_drops,
                             Clock::time_point now) {
  const uint64_t received = metrics.frames_received.load(), published = metrics.frames_published.load();
  const uint64_t dropped = metrics.frames_dropped.load();
  const LatencyHistogram::Buckets processing = metrics.receive_to_publish.bucket_counts();
  const RateSampler::Interval out = published_.sample(published, now);
  const uint64_t new_subscriber_drops = subscriber_drops > subscriber_drops_ ? subscriber_drops - subscriber_drops_ : 0;
  char line[256];
  std::snprintf(line, sizeof line,
                "status %.*s: %llu frames in, %llu out (%.1f/s) in %.0f s; processing p99 <= %.2f ms; %zu subscribers; dropped %llu in "
                "the pipeline, %llu for subscribers",
                static_cast<int>(subject.size()), subject.data(), static_cast<unsigned long long>(received - received_),
                static_cast<unsigned long long>(out.count), out.per_second(), out.seconds,
                p99_upper_bound_ms(processing, processing_), subscribers, static_cast<unsigned long long>(dropped - dropped_),
                static_cast<unsigned long long>(new_subscriber_drops));
  received_ = received;
  dropped_ = dropped;
  processing_ = processing;
  subscriber_drops_ = subscriber_drops;
  return line;
}

}  // namespace skinstream::server
