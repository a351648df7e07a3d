#pragma once
// A Vicon DataStream server streaming a recorded Capture, so that unmodified Vicon SDK clients
// (and skinstream's own ViconSource) can be tested and benchmarked without a capture stage.
//
// Per client: the server sends ObjectEnums (the types it offers) at once; the client answers with
// the subset it wants (ObjectEnums, and optionally Filter), then asks for frames:
//   RequestFrame{true}                     ServerPush: every frame from then on
//   RequestFrame{false} / RequestNextFrame ClientPull: one frame per request, the newest not yet
//                                          sent to that client (waits for the next if none)
//   Ping                                   echoed back
//   StartMulticastSender / Stop...         UDP datagrams, one whole packet each, to group:port
// A client's first frame also carries StreamInfo and SubjectInfo, and so does the first frame
// after the subjects listed changed (a subject came or went); every datagram carries them.
//
// Several recordings stream as several subjects of one stream, each frame holding one frame of
// each (protocol/vicon/vicon_capture_encoder.h: a subject whose recording has no marker in a frame is
// not listed in it).
//
// Frames leave on absolute steady-clock deadlines (start + k * period / speed), so the stream
// does not drift (server/replay/replay_timeline.h). The timeline starts when the first client
// asks for a frame (or at start() with start_on_first_request = false). Frame numbers, as the
// SDK shows them, are capture.first_frame + k, where k keeps counting across loops so numbers
// never go back.
//
// Each client has a bounded queue: when it is full the oldest waiting frame is dropped (the
// newest wins) and counted, so a slow client never delays the others. A client sending malformed
// input is closed and counted; the others go on.
// Out of file descriptors, accepts pause and resume as the daemon's do (server/listener.h). At
// most max_clients are served at once (more are closed as they come, counted), and a client's
// packet may be at most kMaxClientPacketBytes (20 clients each holding most of a 16 MiB packet
// once took 350 MB). StartMulticastSender sends to a multicast group, or to the asking client's
// own address, and only while that client stays (1,000 requests for other unicast destinations
// were served after their clients left: 0.75 of a core, 5.4 MB/s each); at most
// max_multicast_destinations at once.
//
// Threading: all member functions run on the io_context's thread (or before it runs); stats()
// may be read from any thread.

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/capture.h"
#include "protocol/vicon/vicon_capture_encoder.h"
#include "protocol/vicon/vicon_datastream.h"
#include "server/asio.h"

namespace skinstream::server {

struct ViconServerOptions {
  std::string bind_address = "0.0.0.0";
  uint16_t port = vicon::kDefaultPort;  // 0: an ephemeral port (see ViconServer::port())
  std::string subject_name = "subject";  // of a single recording
  double rate_hz = 0.0;  // announced and streamed rate; 0: the capture's
  double speed = 1.0;    // 2: twice as fast in wall time (StreamInfo still announces rate_hz)
  bool loop = false;
  bool start_on_first_request = true;
  size_t max_queued_frames = 4;     // per client, frames waiting behind the one being written
  int socket_send_buffer_bytes = 0;  // SO_SNDBUF per client; 0: the system's default
  // TCP congestion control per client (server/tcp_congestion.h); empty: the system's. Not reno
  // by default as for the daemon's subscribers: a frame of 350 markers is small enough to leave
  // at once even under BBR, and reno measured no different here (README).
  std::string tcp_congestion;
  int multicast_ttl = 1;
  size_t max_clients = 64;                 // served at once
  size_t max_multicast_destinations = 16;  // StartMulticastSender destinations at once
};

struct ViconServerStats {
  std::atomic<uint64_t> clients_accepted{0};
  std::atomic<uint64_t> clients_open{0};
  std::atomic<uint64_t> bad_clients{0};      // closed for malformed input
  std::atomic<uint64_t> frames_produced{0};
  std::atomic<uint64_t> frame_packets_sent{0};
  std::atomic<uint64_t> frames_dropped{0};   // newest-wins drops in client queues
  std::atomic<uint64_t> datagrams_sent{0};
  std::atomic<uint64_t> datagrams_too_large{0};
  std::atomic<uint64_t> clients_refused{0};             // beyond max_clients
  std::atomic<uint64_t> multicast_requests_refused{0};  // another host's unicast address, or too many
};

// The largest packet a client may send (its requests are a few bytes; ObjectEnums a few hundred).
inline constexpr uint32_t kMaxClientPacketBytes = 64 * 1024;

class ViconServer {
 public:
  using FrameHook = std::function<void(uint32_t frame_number, int64_t send_time_ns)>;

  // The captures must outlive the server. Everything but stats() runs on the io_context's
  // thread (or before it runs / after it stopped), destruction included: the sessions live there.
  // Throws std::invalid_argument for recordings that cannot share a stream (different rates).
  ViconServer(asio::io_context& io, std::vector<ReplaySubject> subjects, ViconServerOptions options);
  // One recording, streamed as the subject options.subject_name.
  ViconServer(asio::io_context& io, const Capture& capture, ViconServerOptions options);
  ~ViconServer();
  ViconServer(const ViconServer&) = delete;
  ViconServer& operator=(const ViconServer&) = delete;

  void start();  // binds and listens; throws std::runtime_error naming the address on failure
  void stop();   // closes the listener and every client; safe to call twice
  uint16_t port() const;

  // Called for each frame just before it is handed to the clients and multicast destinations,
  // with the system clock (ns since epoch) at that moment: the frame's send time.
  void set_frame_hook(FrameHook hook);
  // Called once when the last frame has been produced (never with loop).
  void set_on_finished(std::function<void()> on_finished);

  // Streams to group:port over UDP as if a client had sent StartMulticastSender.
  void start_multicast(const std::string& address, uint16_t port);

  bool finished() const;
  bool all_clients_idle() const;  // nothing queued for any client
  const ViconServerStats& stats() const;

 private:
  struct State;
  std::shared_ptr<State> state_;
};

}  // namespace skinstream::server
