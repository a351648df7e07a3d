#pragma once
// The line a person watching the daemon's log reads every few seconds, per subject: frames in
// and out over the interval and their rate, the processing p99 over the interval (receive to
// publish, as a bucket's upper bound), subscribers, and what was dropped since the last line.
#include <chrono>
#include <string>
#include <string_view>

#include "server/metrics/metrics.h"
#include "server/metrics/rate_sampler.h"

namespace skinstream::server {

class StatusLine {
 public:
  using Clock = RateSampler::Clock;
  // The line for the interval since the previous call (since construction, the first time).
  // `subscriber_drops`: frames dropped so far for the subscribers connected now (a subscriber
  // that left takes its count with it, so a fall is read as no new drops).
  std::string next(std::string_view subject, const Metrics& metrics, size_t subscribers, uint64_t subscriber_drops, Clock::time_point now);

 private:
  RateSampler published_;  // frames out, their rate and the interval's length
  uint64_t received_ = 0, dropped_ = 0;
  LatencyHistogram::Buckets processing_{};
  uint64_t subscriber_drops_ = 0;
};

}  // namespace skinstream::server
