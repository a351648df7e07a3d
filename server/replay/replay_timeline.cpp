#include "server/replay/replay_timeline.h"

#include <chrono>

namespace skinstream::server {

ReplayTimeline::ReplayTimeline(asio::io_context& io, double rate_hz, double speed, uint64_t frame_count, bool loop)
    : timer_(io), rate_hz_(rate_hz), speed_(speed > 0.0 ? speed : 1.0), frame_count_(frame_count), loop_(loop) {}

void ReplayTimeline::start() {
  if (started_ || stopped_ || frame_count_ == 0 || !(rate_hz_ > 0.0)) return;
  started_ = true;
  start_ = asio::steady_timer::clock_type::now();
  schedule();
}

void ReplayTimeline::stop() {
  stopped_ = true;
  timer_.cancel();
}

void ReplayTimeline::schedule() {
  const std::chrono::duration<double> offset(static_cast<double>(next_) / (rate_hz_ * speed_));
  timer_.expires_at(start_ + std::chrono::duration_cast<asio::steady_timer::clock_type::duration>(offset));
  timer_.async_wait([this, alive = std::weak_ptr<bool>(alive_)](const boost::system::error_code& ec) {
    if (ec || alive.expired() || stopped_) return;
    const uint64_t k = next_++;
    if (on_frame_) on_frame_(k);
    if (stopped_) return;
    if (!loop_ && next_ >= frame_count_) {
      finished_ = true;
      if (on_finished_) on_finished_();
      return;
    }
    schedule();
  });
}

}  // namespace skinstream::server
