#include "server/ingest/source_reconnection.h"

#include <algorithm>
#include <chrono>

namespace skinstream::server {

SourceReconnection::SourceReconnection(asio::io_context& io, SourceSink& sink, double initial_seconds,
                                       double max_seconds)
    : sink_(sink),
      timer_(io),
      initial_seconds_(initial_seconds),
      max_seconds_(max_seconds),
      backoff_seconds_(initial_seconds) {}

void SourceReconnection::failed(const std::string& reason, std::function<void()> retry, SourceState state) {
  streaming_ = false;
  if (!disconnected_reported_) {
    disconnected_reported_ = true;
    sink_.on_source_state(state, reason);
  }
  timer_.expires_after(std::chrono::duration_cast<asio::steady_timer::duration>(
      std::chrono::duration<double>(backoff_seconds_)));
  backoff_seconds_ = std::min(backoff_seconds_ * 2.0, max_seconds_);
  timer_.async_wait([retry = std::move(retry)](const boost::system::error_code& ec) {
    if (!ec) retry();
  });
}

void SourceReconnection::frame_arrived(std::string_view where) {
  if (streaming_) return;
  streaming_ = true;
  disconnected_reported_ = false;
  backoff_seconds_ = initial_seconds_;
  sink_.on_source_state(SourceState::Streaming, where);
}

void SourceReconnection::cancel() { timer_.cancel(); }

}  // namespace skinstream::server
