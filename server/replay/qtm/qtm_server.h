#pragma once
// A QTM RT server streaming recorded captures as Qualisys Track Manager streams a measurement in
// real time, so that unmodified QTM RT clients (the Qualisys SDKs, the npm package qualisys-rt)
// and skinstream's own QtmSource run without a capture stage. It speaks the little-endian port
// (protocol/qtm/qtm_rt.h), 22223 by default.
//
// Per client: the welcome ("QTM RT Interface connected") at once; then commands, each answered
// as QTM does: Version 1.8-1.28 ("Version set to 1.N"), QTMVersion, ByteOrder, GetState (an
// Event: RT from file started, or stopped once a replay has ended), GetParameters General 3D
// (XML: the frequency and the labels, protocol/qtm/qtm_parameters.h), GetCurrentFrame, StreamFrames
// [AllFrames|Frequency:N|FrequencyDivisor:N] [UDP[:address]:port] 3D 3DNoLabels, StreamFrames Stop.
// Other commands get an Error packet. Several recordings are several actors whose labels carry
// their prefix (protocol/qtm/qtm_labels.h).
//
// Frames leave on the replay clock (server/replay/replay_timeline.h); the timeline starts when
// the first client asks for frames (StreamFrames) unless start_on_first_request is false. At the
// end of a recording (without loop) streaming clients get the event "RT from file stopped" and a
// NoMoreData packet.
//
// Each client has a bounded queue: when it is full the oldest waiting frame is dropped (the
// newest wins) and counted, so a slow client never delays the others. Command replies are
// bounded too: with max_queued_replies waiting, the client's next commands are not read until
// it reads its replies (20,000 GetParameters once took 630 MB). A client sending malformed
// packets is closed and counted; the others go on. At most max_clients are served at once (more
// are closed as they come, counted), and accepts pause when descriptors run out (the shared
// Listener), instead of retrying at once on a full core. Frames go over UDP only to the address
// of the client that asked (StreamFrames ... UDP:address:port naming another is refused): the
// server is no one's relay toward a third party.
//
// Threading: everything but stats() runs on the io_context's thread (or before it runs).

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "protocol/files/replay_subject.h"
#include "protocol/qtm/qtm_rt.h"
#include "server/asio.h"

namespace skinstream::server {

struct QtmServerOptions {
  std::string bind_address = "0.0.0.0";
  uint16_t port = qtm::kLittleEndianPort;  // 0: an ephemeral port (see QtmServer::port())
  double rate_hz = 0.0;  // announced and streamed rate; 0: the first recording's
  double speed = 1.0;    // 2: twice as fast in wall time
  bool loop = false;
  bool start_on_first_request = true;
  size_t max_queued_frames = 4;  // per client, frames waiting behind the one being written
  size_t max_queued_replies = 64;  // per client, command replies waiting; then its commands wait
  size_t max_clients = 64;         // served at once
  // Stream indices [first, end) recorded as a QTM capture: the events "capture started" before
  // frame `first` and "capture stopped" before frame `end`, as QTM sends them; none by default.
  uint64_t capture_first = 0, capture_end = 0;
};

struct QtmServerStats {
  std::atomic<uint64_t> clients_accepted{0};
  std::atomic<uint64_t> clients_open{0};
  std::atomic<uint64_t> bad_clients{0};  // closed for malformed input
  std::atomic<uint64_t> commands{0};
  std::atomic<uint64_t> commands_refused{0};  // answered with an Error packet
  std::atomic<uint64_t> frames_produced{0};
  std::atomic<uint64_t> frame_packets_sent{0};
  std::atomic<uint64_t> frames_dropped{0};  // newest-wins drops in client queues
  std::atomic<uint64_t> datagrams_sent{0};  // StreamFrames ... UDP
  std::atomic<uint64_t> clients_refused{0};  // beyond max_clients
  std::atomic<uint64_t> reads_paused{0};     // a client's commands left unread while its replies wait
};

class QtmServer {
 public:
  // The captures behind `subjects` must outlive the server.
  QtmServer(asio::io_context& io, std::vector<ReplaySubject> subjects, QtmServerOptions options);
  ~QtmServer();
  QtmServer(const QtmServer&) = delete;
  QtmServer& operator=(const QtmServer&) = delete;

  void start();  // binds and listens; throws std::runtime_error naming the address on failure
  void stop();   // closes the listener and every client; safe to call twice
  uint16_t port() const;

  void set_on_finished(std::function<void()> on_finished);  // once, after the last frame
  // Called on the io thread with each frame's number and the system clock (ns since the epoch)
  // just before it goes out to the first client: the bench's send time.
  using FrameHook = std::function<void(uint32_t frame_number, int64_t send_time_ns)>;
  void set_frame_hook(FrameHook hook);
  bool finished() const;
  bool all_clients_idle() const;  // nothing queued for any client
  const QtmServerStats& stats() const;

 private:
  struct State;
  std::shared_ptr<State> state_;
};

}  // namespace skinstream::server
