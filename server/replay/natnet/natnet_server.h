#pragma once
// A NatNet server streaming recorded captures as Motive streams a take, so that NatNet clients
// and skinstream's own NatNetSource run without a capture stage (protocol/natnet/natnet.h).
//
// Commands arrive on the command port (UDP, 1510 by default) and are answered to their sender:
//   CONNECT               SERVERINFO (this server's NatNet version, data port, multicast group);
//                         unicast: the sender joins the clients frames are sent to
//   REQUEST_MODELDEF      MODELDEF: one marker set per recording, in this server's layout
//   REQUEST_FRAMEOFDATA   the newest frame
//   KEEPALIVE             keeps a unicast client (one silent for client_timeout is dropped)
//   DISCONNECT            drops the client
//   REQUEST (text)        UNRECOGNIZED_REQUEST: a replay takes no text commands
//   anything else         ignored (never answered)
// Frames go to group:data_port (multicast), or to every connected client's command socket
// (unicast, at most max_clients: a CONNECT beyond them is not answered, and counted), on the
// replay clock (server/replay/replay_timeline.h). REQUEST_MODELDEF and REQUEST_FRAMEOFDATA are
// answered only to a sender that CONNECTed (the last max_clients of them): a request from
// anyone else, perhaps with a forged source address, would have the server send a victim ~1,000
// times the bytes it cost. The timeline starts with the
// first CONNECT unless start_on_first_request is false. Malformed datagrams are counted, logged at
// a limited rate and ignored.
//
// Threading: everything but stats() runs on the io_context's thread (or before it runs).

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "protocol/files/replay_subject.h"
#include "protocol/natnet/natnet.h"
#include "server/asio.h"

namespace skinstream::server {

struct NatNetServerOptions {
  std::string bind_address = "0.0.0.0";
  uint16_t command_port = natnet::kCommandPort;  // 0: an ephemeral port (see NatNetServer::command_port())
  uint16_t data_port = natnet::kDataPort;        // multicast destination port, announced in SERVERINFO
  bool multicast = true;
  std::string multicast_group = natnet::kMulticastGroup;
  std::string multicast_interface;  // address of the interface to send from; empty: the system's
  int multicast_ttl = 1;
  natnet::Version version;  // the layout streamed (3.0 to 4.1)
  double rate_hz = 0.0;     // 0: the first recording's
  double speed = 1.0;
  bool loop = false;
  bool start_on_first_request = true;
  std::chrono::milliseconds client_timeout{10'000};  // unicast clients without a keep-alive
  size_t max_clients = 16;                           // unicast clients served, and senders remembered as connected
  // The frames' timestamps as a real capture clock stamps them, for tests and benchmarks of the
  // clients (0: exact): moved by up to +-timestamp_jitter_us, then quantised to the ticks of a
  // timestamp_clock_hz clock (protocol/natnet/natnet_capture_encoder.h).
  double timestamp_jitter_us = 0.0;
  double timestamp_clock_hz = 0.0;
  // The latency the frames' stamps say the capture system had (transmit minus mid-exposure).
  double capture_latency_us = 0.0;
  // Stream indices [first, end) flagged as recorded by Motive (frame params bit 0); none by default.
  uint64_t recording_first = 0, recording_end = 0;
};

struct NatNetServerStats {
  std::atomic<uint64_t> requests{0};
  std::atomic<uint64_t> bad_datagrams{0};
  std::atomic<uint64_t> clients_connected{0};
  std::atomic<uint64_t> clients_timed_out{0};
  std::atomic<uint64_t> frames_produced{0};
  std::atomic<uint64_t> datagrams_sent{0};
  std::atomic<uint64_t> frames_too_large{0};  // over one UDP datagram: not sent
  std::atomic<uint64_t> clients_refused{0};   // CONNECTs beyond max_clients
  std::atomic<uint64_t> requests_not_connected{0};  // model or frame requests from a sender that did not CONNECT
};

class NatNetServer {
 public:
  // The captures behind `subjects` must outlive the server.
  NatNetServer(asio::io_context& io, std::vector<ReplaySubject> subjects, NatNetServerOptions options);
  ~NatNetServer();
  NatNetServer(const NatNetServer&) = delete;
  NatNetServer& operator=(const NatNetServer&) = delete;

  void start();  // binds the command port; throws std::runtime_error naming the address on failure
  void stop();   // safe to call twice
  uint16_t command_port() const;

  void set_on_finished(std::function<void()> on_finished);  // once, after the last frame
  // Called on the io thread with each frame's number and the system clock (ns since the epoch)
  // just before it goes out to the first client: the bench's send time.
  using FrameHook = std::function<void(uint32_t frame_number, int64_t send_time_ns)>;
  void set_frame_hook(FrameHook hook);
  bool finished() const;
  const NatNetServerStats& stats() const;

 private:
  struct State;
  std::shared_ptr<State> state_;
};

}  // namespace skinstream::server
