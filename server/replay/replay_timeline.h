#pragma once
// The clock of a replay server: frame k of a recording leaves at start + k / (rate x speed) on
// the steady clock, so the stream does not drift, and k keeps counting across loops. Shared by
// the Vicon DataStream, QTM RT and NatNet replay servers.
//
// Threading: every member runs on the io_context's thread (or before it runs).

#include <cstdint>
#include <functional>
#include <memory>

#include "server/asio.h"

namespace skinstream::server {

class ReplayTimeline {
 public:
  // on_frame(k) for every frame; on_finished() once after the last one (never with loop).
  ReplayTimeline(asio::io_context& io, double rate_hz, double speed, uint64_t frame_count, bool loop);

  void set_on_frame(std::function<void(uint64_t stream_index)> on_frame) { on_frame_ = std::move(on_frame); }
  void set_on_finished(std::function<void()> on_finished) { on_finished_ = std::move(on_finished); }

  void start();  // the first frame leaves at once; later calls do nothing
  void stop();
  bool started() const { return started_; }
  bool finished() const { return finished_; }
  uint64_t frames_produced() const { return next_; }

 private:
  void schedule();

  asio::steady_timer timer_;
  double rate_hz_;
  double speed_;
  uint64_t frame_count_;
  bool loop_;
  bool started_ = false;
  bool finished_ = false;
  bool stopped_ = false;
  uint64_t next_ = 0;
  asio::steady_timer::clock_type::time_point start_;
  std::function<void(uint64_t)> on_frame_;
  std::function<void()> on_finished_;
  // A frame already due when the timeline is destroyed still has its handler run (with success):
  // the handler checks this before it touches the timeline.
  std::shared_ptr<bool> alive_ = std::make_shared<bool>(true);
};

}  // namespace skinstream::server
