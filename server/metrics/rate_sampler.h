#pragma once
// A running count's rate between two samples: /health's frames/s of a subject and the status
// line's, each sampling at its own pace.
#include <chrono>
#include <cstdint>

namespace skinstream::server {

class RateSampler {
 public:
  using Clock = std::chrono::steady_clock;
  struct Interval {
    uint64_t count = 0;  // counted since the previous sample
    double seconds = 0;  // since the previous sample
    double per_second() const { return seconds > 0 ? static_cast<double>(count) / seconds : 0.0; }
  };

  explicit RateSampler(Clock::time_point start = Clock::now()) : sampled_at_(start) {}

  double seconds_since_sample(Clock::time_point now) const {
    return std::chrono::duration<double>(now - sampled_at_).count();
  }
  // The interval since the previous sample (since construction, the first time); `total` at
  // `now` becomes the previous sample.
  Interval sample(uint64_t total, Clock::time_point now) {
    const Interval interval{total - total_, seconds_since_sample(now)};
    total_ = total;
    sampled_at_ = now;
    return interval;
  }

 private:
  Clock::time_point sampled_at_;
  uint64_t total_ = 0;
};

}  // namespace skinstream::server
