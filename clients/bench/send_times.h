#pragma once
// Send times by frame number, written by the replay server's io thread and read by the
// subscriber threads. A ring of the last kSlots frames (34 s at 120 Hz): a frame still in flight
// after that long is reported as unmatched rather than given a wrong send time.
#include <array>
#include <cstdint>
#include <mutex>
#include <nlohmann/json.hpp>

#include "clients/bench/stall_log.h"

namespace skinstream::bench {

class SendTimes {
 public:
  void record(uint32_t frame_number, int64_t send_ns) {
    std::lock_guard lock(mutex_);
    slots_[frame_number % kSlots] = {frame_number, send_ns};
    // The replay's own regularity: after a stall of this (shared) machine it sends the frames
    // it owes back to back, as a capture system's server would after a hitch; the daemon
    // processes such a burst whole unless it is longer than its mailbox (32 frames).
    if (counting_ && last_send_ns_ > 0) {
      const int64_t gap = send_ns - last_send_ns_;
      max_gap_ns_ = std::max(max_gap_ns_, gap);
      if (gap > 3 * period_ns_) {
        ++gaps_over_3_periods_;
        if (stalls_) stalls_->add_gap(last_send_ns_, "replay", static_cast<double>(gap) / 1e6);
      }
    }
    last_send_ns_ = send_ns;
  }
  // From now on, gaps are counted and those over 3 periods logged to `stalls`.
  void start_counting(int64_t period_ns, StallLog* stalls) {
    std::lock_guard lock(mutex_);
    period_ns_ = period_ns;
    stalls_ = stalls;
    counting_ = true;
  }
  nlohmann::json regularity() const {
    std::lock_guard lock(mutex_);
    return {{"max_gap_ms", static_cast<double>(max_gap_ns_) / 1e6}, {"gaps_over_3_frame_periods", gaps_over_3_periods_}};
  }
  // 0 when the frame number was never sent (or is too old).
  int64_t find(uint32_t frame_number) const {
    std::lock_guard lock(mutex_);
    const Slot& slot = slots_[frame_number % kSlots];
    return slot.frame_number == frame_number ? slot.send_ns : 0;
  }

 private:
  static constexpr uint32_t kSlots = 4096;
  struct Slot {
    uint32_t frame_number = 0;
    int64_t send_ns = 0;
  };
  mutable std::mutex mutex_;
  std::array<Slot, kSlots> slots_{};
  bool counting_ = false;
  StallLog* stalls_ = nullptr;
  int64_t period_ns_ = 0, last_send_ns_ = 0, max_gap_ns_ = 0;
  uint64_t gaps_over_3_periods_ = 0;
};

}  // namespace skinstream::bench
