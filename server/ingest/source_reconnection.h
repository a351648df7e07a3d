#pragma once
// How a network source reports its connection and comes back after a failure: Disconnected (or
// Stalled) is reported once per outage (with the first reason), a retry follows after a backoff that doubles
// from initial_seconds to max_seconds, and once frames flow again Streaming is reported once and
// the backoff starts from initial_seconds again. Shared by the Vicon DataStream, QTM RT and
// NatNet sources.
//
// Threading: every member runs on the source's io_context thread.

#include <functional>
#include <string>
#include <string_view>

#include "server/asio.h"
#include "server/ingest/source_frame.h"

namespace skinstream::server {

class SourceReconnection {
 public:
  SourceReconnection(asio::io_context& io, SourceSink& sink, double initial_seconds, double max_seconds);

  // The connection failed: report `state` (once per outage: Disconnected, or Stalled for a
  // source that went silent), then `retry` after the backoff.
  void failed(const std::string& reason, std::function<void()> retry, SourceState state = SourceState::Disconnected);
  // A frame arrived: Streaming is reported on the first one of a connection.
  void frame_arrived(std::string_view where);
  // Frames stopped without a failure (a replay ended): the next frame reports Streaming again.
  void frames_stopped() { streaming_ = false; }
  bool streaming() const { return streaming_; }
  void cancel();  // the pending retry, if any

 private:
  SourceSink& sink_;
  asio::steady_timer timer_;
  double initial_seconds_, max_seconds_, backoff_seconds_;
  bool streaming_ = false;
  bool disconnected_reported_ = false;
};

}  // namespace skinstream::server
