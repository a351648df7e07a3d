#include "server/ingest/frame_source.h"

namespace skinstream::server {

const char* to_string(SourceState state) {
  switch (state) {
    case SourceState::Connecting: return "connecting";
    case SourceState::Streaming: return "streaming";
    case SourceState::Disconnected: return "disconnected";
    case SourceState::Finished: return "finished";
    case SourceState::Stalled: return "stalled";
  }
  return "unknown";
}

}  // namespace skinstream::server
