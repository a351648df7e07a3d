#pragma once
// A source of capture frames (Vicon DataStream client, multicast receiver, file replay, ...) as
// the daemon starts and stops it. What a source hands on, and to whom: SourceFrame and
// SourceSink (server/ingest/source_frame.h).

#include "server/ingest/source_frame.h"

namespace skinstream::server {

// A source that can be started and stopped from the daemon's control thread.
class FrameSource {
 public:
  virtual ~FrameSource() = default;
  virtual void start() = 0;  // begins asynchronous work on the io_context; returns at once
  virtual void stop() = 0;   // cancels it; safe to call twice
};

}  // namespace skinstream::server
