#pragma once
// The daemon's NatNet client: asks Motive (or skinstream-replay --protocol natnet) on its command
// port (UDP 1510) for its server info and model definitions, then receives frames of data,
// multicast (group and data port as the server info says, joined on `interface_address`) or
// unicast (on the command socket, kept alive every second), and hands each one to a SourceSink as
// a SourceFrame, decoded only: matching labels to our subjects comes after.
//
// Subjects are the marker sets of the model definitions (Motive's "all" set, which repeats every
// labelled marker, is left out), their labels the marker names; positions are converted from
// metres to millimetres, NaN stays occluded. Unlabelled points are the labelled-markers entries
// without a model (their point cloud id), or the legacy other markers when there are none. A
// frame naming a marker set the definitions do not know (or with another marker count), or
// flagging that the tracked models changed, asks for the definitions again (at most once a
// second: model_request_interval) and is passed on without that set.
//
// The command socket (which also takes the unicast frames) is bound to `bind_address`, or, when
// that is 0.0.0.0, to this host's address toward the server, and takes datagrams from the
// server's address only: others are counted and dropped (on_bad_input "foreign_datagram"), so a
// stranger on the network can neither send frames nor change the model definitions (one bound to
// 0.0.0.0 and taking anyone's once made the subject absent with one forged MODELDEF).
//
// The NatNet layout (3.x, 4.0, 4.1) is the server's, from its server info. No server info or no
// model definitions within reply_timeout reports Disconnected; no frame for stall_timeout once
// they came (a server that went silent, or sends only other datagrams) reports Stalled; both ask
// again after a backoff of 0.25 s doubling to 5 s. NatNet announces no frame rate: it is
// estimated from the frames' numbers and timestamps over a long window (source_rate_estimate.h).
// Malformed datagrams are reported (on_bad_input) and dropped. After the first frames, receiving
// a frame allocates nothing.

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>

#include "protocol/natnet/natnet.h"
#include "server/asio.h"
#include "server/ingest/frame_source.h"
#include "server/ingest/source_frame.h"

namespace skinstream::server {

struct NatNetSourceOptions {
  std::string host = "127.0.0.1";
  uint16_t command_port = natnet::kCommandPort;
  std::string interface_address = "0.0.0.0";  // where to join the multicast group
  std::string bind_address = "0.0.0.0";  // the command socket's; 0.0.0.0: this host's address toward the server
  double initial_backoff_seconds = 0.25;
  double max_backoff_seconds = 5.0;
  std::chrono::milliseconds reply_timeout{3000};  // server info, then model definitions
  std::chrono::milliseconds stall_timeout{1000};  // without a frame once streaming; 0: wait forever
  std::chrono::milliseconds keep_alive_interval{1000};
  std::chrono::milliseconds model_request_interval{1000};  // at most one re-request of the definitions
};

class NatNetSource : public FrameSource {
 public:
  NatNetSource(asio::io_context& io, NatNetSourceOptions options, SourceSink& sink);
  ~NatNetSource() override;

  void start() override;
  void stop() override;

 private:
  struct State;
  std::shared_ptr<State> state_;
};

}  // namespace skinstream::server
