#pragma once
// The capture system the bench plays: a replay server of one of the three protocols streaming
// the recording in this process (Vicon DataStream over TCP, QTM RT over TCP, NatNet over UDP
// unicast), each noting when every frame number leaves, for the end-to-end latency.
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "protocol/files/replay_subject.h"
#include "server/asio.h"

namespace skinstream::bench {

enum class CaptureProtocol { Vicon, Qtm, NatNet };
const char* to_string(CaptureProtocol protocol);

struct ReplayEngineOptions {
  CaptureProtocol protocol = CaptureProtocol::Vicon;
  std::string bind_address = "127.0.0.1";
  std::string tcp_congestion;  // Vicon's connection to the daemon ("" = the system's)
  double natnet_timestamp_jitter_us = 0.0;  // NatNet: the replay's clock (server/replay/natnet/natnet_server.h)
  double natnet_clock_hz = 0.0;
};

class ReplayEngine {
 public:
  using FrameHook = std::function<void(uint32_t frame_number, int64_t send_time_ns)>;
  // Looping, on an ephemeral port: each recording one subject (marker set) of the stream; the
  // recordings must outlive the engine.
  ReplayEngine(server::asio::io_context& io, const std::vector<ReplaySubject>& subjects, const ReplayEngineOptions& options);
  ~ReplayEngine();
  void set_frame_hook(FrameHook hook);  // before start()
  void start();
  // The daemon's command-line option that makes it a client of this server.
  std::string daemon_source_option() const;
  uint64_t frames_sent() const;
  uint64_t frames_dropped() const;  // frames a slow client lost (Vicon, QTM), or too large to send (NatNet)

 private:
  struct Servers;
  ReplayEngineOptions options_;
  std::unique_ptr<Servers> servers_;
};

}  // namespace skinstream::bench
