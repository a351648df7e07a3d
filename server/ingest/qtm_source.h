#pragma once
// The daemon's QTM RT client: connects to Qualisys Track Manager (or skinstream-replay --protocol
// qtm) on its little-endian port (22223, QTM's base port + 1) and hands every 3D frame to a
// SourceSink as a SourceFrame, decoded only: matching labels to our subjects comes after.
//
// Handshake: the welcome, `Version 1.19`, `GetParameters General 3D` (the frequency and the
// labels), then `StreamFrames AllFrames 3D 3DNoLabels` (or with `UDP:port`, the frames arrive as
// datagrams on a local UDP port while commands stay on TCP). The labels are grouped into subjects
// by their actor prefix (protocol/qtm/qtm_labels.h); a new parameters XML (QTM sends one after
// `GetParameters`, which is asked again when QTM reports an event that may change the labels, or
// when a frame's marker count disagrees with them, at most once per parameters_request_interval)
// changes `subjects` and bumps structure_version. NaN positions are occluded; other non-finite values are
// reported and passed on as NaN.
//
// Any failure (refused, reset, end of stream, malformed packet, an Error answer during the
// handshake, a handshake not done within handshake_timeout) closes the connection, reports
// Disconnected with the reason and retries after a backoff of 0.25 s doubling to 5 s, back to
// 0.25 s once frames flow. A server that sends no frame for stall_timeout after StreamFrames
// (connected, but silent: a server that never answered kept the daemon "connecting" forever, one
// that stopped with its connection open was shown streaming) is reported Stalled and retried the
// same way. A NoMoreData packet (a measurement or RT from file ended) reports Finished and waits
// for more, however long.
// After the first frames, receiving a frame allocates nothing.

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>

#include "protocol/qtm/qtm_rt.h"
#include "server/asio.h"
#include "server/ingest/frame_source.h"
#include "server/ingest/source_frame.h"

namespace skinstream::server {

struct QtmSourceOptions {
  std::string host = "127.0.0.1";
  uint16_t port = qtm::kLittleEndianPort;
  uint16_t udp_port = 0;  // > 0: frames as UDP datagrams to this local port instead of TCP
  double initial_backoff_seconds = 0.25;
  double max_backoff_seconds = 5.0;
  std::chrono::milliseconds handshake_timeout{3000};  // connected to StreamFrames sent
  std::chrono::milliseconds stall_timeout{1000};      // without a frame while streaming; 0: wait forever
  std::chrono::milliseconds parameters_request_interval{1000};  // while streaming, GetParameters at most this often
};

class QtmSource : public FrameSource {
 public:
  QtmSource(asio::io_context& io, QtmSourceOptions options, SourceSink& sink);
  ~QtmSource() override;

  void start() override;
  void stop() override;

 private:
  struct State;
  std::shared_ptr<State> state_;
};

}  // namespace skinstream::server
