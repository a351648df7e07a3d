#pragma once
// The Vicon DataStream over UDP: every datagram is one whole packet (a Vicon server asked with
// StartMulticastSender sends them to a group, by default port 44801). Receive-only, so nothing is
// negotiated: each datagram carries StreamInfo and SubjectInfo (skinstream-replay always sends
// them; a Vicon server does) and frames are assembled as ViconSource does.
//
// A malformed datagram is reported (on_bad_input) and dropped; the stream goes on. Streaming is
// reported on the first frame, Disconnected after `silence_timeout_seconds` without one.
// The address may be a multicast group (joined on `interface_address`) or a unicast address
// of this host (then nothing is joined: the server sends straight to us).

#include <memory>
#include <string>

#include "protocol/vicon/vicon_datastream.h"
#include "server/asio.h"
#include "server/ingest/frame_source.h"

namespace skinstream::server {

struct ViconMulticastSourceOptions {
  std::string group = "239.255.42.1";   // or a local unicast address, e.g. 127.0.0.1
  uint16_t port = vicon::kDefaultMulticastPort;
  std::string interface_address = "0.0.0.0";
  double silence_timeout_seconds = 1.0;
  vicon::DescriptionLimits limits{};  // the subjects a datagram may carry
};

class ViconMulticastSource : public FrameSource {
 public:
  ViconMulticastSource(asio::io_context& io, ViconMulticastSourceOptions options, SourceSink& sink);
  ~ViconMulticastSource() override;

  void start() override;  // binds the port (reporting Disconnected with the reason on failure)
  void stop() override;

  uint16_t bound_port() const;  // after start() ran on the io_context (port 0 picks one)

 private:
  struct State;
  std::shared_ptr<State> state_;
};

}  // namespace skinstream::server
