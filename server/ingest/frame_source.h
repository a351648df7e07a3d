#pragma once
// What every marker source (Vicon DataStream client, multicast receiver, file replay) talks to.
// Sources run on the daemon's network io_context and call the sink from that thread; the sink
// must not block (the pipeline takes the newest frame from it).

#include <string_view>

#include "server/ingest/marker_frame.h"
#include "server/ingest/source_frame.h"

namespace skinstream::server {

// SourceState and the SourceSink that replaces FrameSink once every source hands on
// SourceFrames: server/ingest/source_frame.h.

class FrameSink {
 public:
  virtual ~FrameSink() = default;
  // A complete frame. The reference is valid only during the call: copy what is needed.
  virtual void on_frame(const MarkerFrame& frame) = 0;
  virtual void on_source_state(SourceState state, std::string_view detail) = 0;
  // Input that was dropped: a malformed or truncated packet, an unknown object, a short read.
  // `what` is a short fixed category for metrics ("malformed_packet", "unknown_object", ...),
  // `detail` the human-readable reason for the (rate-limited) log.
  virtual void on_bad_input(std::string_view what, std::string_view detail) = 0;
  // A labelled marker name the subject does not have (reported once per name by the source).
  virtual void on_unknown_label(std::string_view name) = 0;
};

// A source that can be started and stopped from the daemon's control thread.
class FrameSource {
 public:
  virtual ~FrameSource() = default;
  virtual void start() = 0;  // begins asynchronous work on the io_context; returns at once
  virtual void stop() = 0;   // cancels it; safe to call twice
};

}  // namespace skinstream::server
