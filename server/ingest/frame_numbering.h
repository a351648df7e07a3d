#pragma once
// Frames the source numbered but never delivered. A capture system numbers its frames one by one
// (Vicon's frame number, QTM's, NatNet's); a jump says frames were lost on the way: a Vicon
// server that skips frames for a client that reads slowly, UDP multicast losing datagrams, a
// source that stalled. The daemon cannot get them back, but the operator should see that the
// preview is not every frame. A number that goes back, repeats, or jumps by more than a minute of
// frames is a new numbering (the source restarted, a replay looped), not a loss.

#include <cstdint>

namespace skinstream::server {

class FrameNumbering {
 public:
  // Jumps beyond this many frames are a new numbering (a minute at 120 Hz, or more at higher rates).
  static constexpr uint32_t kMaxCountedJump = 120 * 60;

  struct Step {
    uint32_t skipped = 0;   // numbers between the previous frame and this one
    bool renumbered = false;  // not the continuation of the previous frame's numbering
  };

  // The next frame's number; wraps at 2^32 as the sources' counters do.
  Step next(uint32_t frame_number, double rate_hz) {
    Step step;
    if (has_previous_) {
      const uint32_t jump = frame_number - previous_;  // modulo 2^32
      const double minute = rate_hz > 0 && rate_hz < 1e6 ? rate_hz * 60.0 : 0.0;  // a sane rate only
      const uint32_t max_jump = minute > kMaxCountedJump ? static_cast<uint32_t>(minute) : kMaxCountedJump;
      if (jump >= 1 && jump <= max_jump) step.skipped = jump - 1;
      else step.renumbered = true;
    }
    previous_ = frame_number;
    has_previous_ = true;
    return step;
  }
  // A new take (reconnect, a replay's loop): the next number continues nothing.
  void restart() { has_previous_ = false; }

 private:
  uint32_t previous_ = 0;
  bool has_previous_ = false;
};

}  // namespace skinstream::server
