#pragma once
// The frame rate of a source that stamps its frames but does not announce its rate (NatNet: each
// frame carries its number and a timestamp). Taken from a long window, never from one pair of
// frames: a capture clock's timestamps jitter (+-20 us is ordinary) or are quantised (83,333 or
// 83,334 ticks of a 10 MHz clock a frame at 120 Hz), and a rate read from each pair of frames
// changed every frame, rebuilding the pipeline's gap filler every time.
//
// The rate is the frames counted over a window of at least kWindowSeconds of the source's own
// clock, within kSnap of a whole number of Hz taken as that number (so 119.88 Hz stays 119.88),
// and otherwise rounded to 0.01 Hz. The first estimate, over kFirstWindowSeconds, is provisional:
// the first whole window replaces it. After that a new estimate replaces the rate only when it
// differs by more than kChange and the next window agrees with it: jitter and quantisation never
// change it; an operator switching 120 Hz to 240 Hz changes it once, about two seconds later. A
// frame number or timestamp that goes back, repeats, or jumps more than a window ahead starts a new
// window (a restart, a loop, a pause), keeping the rate. Non-finite or absurd estimates are ignored.

#include <cstdint>

namespace skinstream::server {

class SourceRateEstimate {
 public:
  static constexpr double kFirstWindowSeconds = 0.5;
  static constexpr double kWindowSeconds = 1.0;
  static constexpr double kChange = 0.005;  // relative: a smaller difference is the same rate
  // Relative distance to a whole number of Hz: twice what +-20 us of jitter moves the first
  // estimate (4e-5 s over half a second), a quarter of 120 Hz's distance to 119.88.
  static constexpr double kSnap = 2e-4;
  static constexpr double kMaxRateHz = 10'000.0;

  // Frame `number` was captured at `seconds` on the source's clock. Returns the rate, 0 until the
  // first window closes.
  double add(int64_t number, double seconds);
  double rate_hz() const { return rate_hz_; }
  // A new connection: the next frame continues nothing, and the rate is found again.
  void reset();

 private:
  void start_window(int64_t number, double seconds);

  bool started_ = false;
  int64_t window_number_ = 0, last_number_ = 0;
  double window_seconds_ = 0.0, last_seconds_ = 0.0;
  double rate_hz_ = 0.0;
  bool provisional_ = false;   // the rate is the first, short window's
  double candidate_hz_ = 0.0;  // a different rate one window saw, waiting for the next to agree
};

}  // namespace skinstream::server
