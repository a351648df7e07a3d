#pragma once
// The lifecycle the Vicon DataStream, QTM RT and NatNet sources share, over their connection
// State (held by shared_ptr, living on the io_context): start reports Connecting and connects on
// the io thread; a failure of the current connection (by generation) closes it and retries after
// the backoff; stop, once, cancels the retry and closes the sockets. State provides io, sink,
// stopped, generation, reconnection, where(), connect() and close_sockets().
#include <cstdint>
#include <memory>
#include <string>

#include "server/asio.h"
#include "server/ingest/source_frame.h"

namespace skinstream::server {

template <typename State>
void start_source(const std::shared_ptr<State>& state) {
  asio::post(state->io, [state] {
    if (state->stopped) return;
    state->sink.on_source_state(SourceState::Connecting, state->where());
    state->connect();
  });
}

template <typename State>
void stop_source(const std::shared_ptr<State>& state) {
  if (state->stopped.exchange(true)) return;
  asio::post(state->io, [state] {
    state->reconnection.cancel();
    state->close_sockets();
  });
}

// Ends connection `gen` (nothing if it is already over) and schedules the next one; reports
// `reported` (Disconnected, or Stalled for a connection that went silent) once per outage.
template <typename State>
void fail_connection(const std::shared_ptr<State>& state, uint64_t gen, const std::string& reason,
                     SourceState reported = SourceState::Disconnected) {
  if (state->stopped || gen != state->generation) return;
  ++state->generation;
  state->close_sockets();
  state->reconnection.failed(
      reason,
      [state] {
        if (!state->stopped) state->connect();
      },
      reported);
}

}  // namespace skinstream::server
