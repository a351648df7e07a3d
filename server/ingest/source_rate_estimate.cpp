#include "server/ingest/source_rate_estimate.h"

#include <cmath>

namespace skinstream::server {
namespace {

double snapped(double hz) {
  const double whole = std::round(hz);
  if (whole > 0.0 && std::abs(hz - whole) <= SourceRateEstimate::kSnap * hz) return whole;
  return std::round(hz * 100.0) / 100.0;
}

bool same_rate(double a, double b) { return std::abs(a - b) <= SourceRateEstimate::kChange * b; }

}  // namespace

void SourceRateEstimate::reset() {
  started_ = false;
  rate_hz_ = 0.0;
  provisional_ = false;
  candidate_hz_ = 0.0;
}

void SourceRateEstimate::start_window(int64_t number, double seconds) {
  started_ = true;
  window_number_ = last_number_ = number;
  window_seconds_ = last_seconds_ = seconds;
}

double SourceRateEstimate::add(int64_t number, double seconds) {
  if (!std::isfinite(seconds)) return rate_hz_;
  const bool continues = started_ && number > last_number_ && seconds > last_seconds_ &&
                         seconds - last_seconds_ <= kWindowSeconds;
  if (!continues) {
    start_window(number, seconds);
    return rate_hz_;
  }
  last_number_ = number;
  last_seconds_ = seconds;
  const double span = seconds - window_seconds_;
  if (span < (rate_hz_ > 0.0 ? kWindowSeconds : kFirstWindowSeconds)) return rate_hz_;
  const double estimate = static_cast<double>(number - window_number_) / span;
  start_window(number, seconds);
  if (!(estimate > 0.0 && estimate <= kMaxRateHz)) return rate_hz_;
  const double hz = snapped(estimate);
  if (rate_hz_ == 0.0 || provisional_) {
    provisional_ = rate_hz_ == 0.0;  // the first window's is provisional; the next one's is the rate
    rate_hz_ = hz;
    candidate_hz_ = 0.0;
  } else if (same_rate(hz, rate_hz_)) {
    candidate_hz_ = 0.0;
  } else if (candidate_hz_ > 0.0 && same_rate(hz, candidate_hz_)) {
    rate_hz_ = hz;
    candidate_hz_ = 0.0;
  } else {
    candidate_hz_ = hz;
  }
  return rate_hz_;
}

}  // namespace skinstream::server
