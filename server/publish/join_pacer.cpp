#include "server/publish/join_pacer.h"

#include <algorithm>

namespace skinstream::server {

namespace {

std::chrono::nanoseconds time_for(size_t bytes, double bytes_per_second) {
  return std::chrono::nanoseconds(static_cast<int64_t>(static_cast<double>(bytes) / bytes_per_second * 1e9));
}

}  // namespace

JoinPacer::JoinPacer(double bytes_per_second, size_t burst_bytes)
    : bytes_per_second_(bytes_per_second), burst_(time_for(burst_bytes, bytes_per_second)) {}

std::chrono::nanoseconds JoinPacer::reserve(size_t bytes, Clock::time_point now) {
  std::lock_guard lock(mutex_);
  // (The generic cell rate algorithm.) After the bytes reserved before, or now if they have gone.
  next_free_ = std::max(next_free_, now) + time_for(bytes, bytes_per_second_);
  // They may go once the link's backlog, these bytes included, is at most a burst.
  const std::chrono::nanoseconds wait = std::max(std::chrono::nanoseconds(0), next_free_ - burst_ - now);
  totals_.bytes += bytes;
  if (wait.count() > 0) {
    ++totals_.delayed;
    totals_.waited_seconds += std::chrono::duration<double>(wait).count();
  }
  return wait;
}

JoinPacer::Totals JoinPacer::totals() const {
  std::lock_guard lock(mutex_);
  return totals_;
}

}  // namespace skinstream::server
