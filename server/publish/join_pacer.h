#pragma once
// The bytes a subscriber is sent when it joins (MeshInfo, about 1.3 MB for the demo body, and the
// Model, about 1 MB; 0.84 MB together packed), paced together for all joiners so that the frames of the
// subscribers already watching go first on the same link. Unpaced, 60 render nodes joining at once put about
// 140 MB on a gigabit link in one burst: the stage switch's queue (or the shaper's) fills and
// every watcher's frames wait behind it (p99 57.6 ms, 116 frames dropped for 4 watchers).
// Paced below the link's rate, the joiners' bytes leave room for the frames and the queue
// stays empty; a joiner waits a little longer for its first frame instead.
//
// A virtual clock: each reservation is scheduled after the ones before it at `rate`, and may
// start up to `burst` bytes early (so one joiner on a quiet stage is not delayed at all).
// Any thread.

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <mutex>

namespace skinstream::server {

class JoinPacer {
 public:
  using Clock = std::chrono::steady_clock;
  // bytes_per_second > 0.
  JoinPacer(double bytes_per_second, size_t burst_bytes);

  // How long to wait, from `now`, before sending `bytes` that are reserved by this call.
  std::chrono::nanoseconds reserve(size_t bytes, Clock::time_point now = Clock::now());

  double bytes_per_second() const { return bytes_per_second_; }
  struct Totals {
    uint64_t bytes = 0;         // reserved in all
    uint64_t delayed = 0;       // reservations that had to wait
    double waited_seconds = 0;  // their waits together
  };
  Totals totals() const;

 private:
  const double bytes_per_second_;
  const std::chrono::nanoseconds burst_;
  mutable std::mutex mutex_;
  Clock::time_point next_free_{};  // when the link would be free of every reserved byte
  Totals totals_;
};

}  // namespace skinstream::server
