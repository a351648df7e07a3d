#pragma once
// What the TCP and WebSocket subscribers share: the Hello handshake (2 s default, then
// positions only), the bounded queue, one write in flight, pacing by Acks for subscribers that
// ask for it, and the per-subscriber counters.
// Everything but offer() runs on the session's io thread (the daemon's, or one of the publish
// threads for a TCP subscriber); offer() is called by the pipeline thread.

#include <array>
#include <atomic>
#include <chrono>
#include <memory>
#include <span>
#include <string>

#include "protocol/subscriber/subscriber_stream.h"
#include "server/asio.h"
#include "server/metrics/metrics.h"
#include "server/pipeline/stream_key.h"
#include "server/publish/handler_slot.h"
#include "server/publish/subscriber_admission.h"
#include "server/publish/subscriber_queue.h"

namespace skinstream::server {

class SubscriberHub;

class SubscriberSession : public std::enable_shared_from_this<SubscriberSession> {
 public:
  // With a JoinPacer (HubOptions): control messages of this size or more are paced, in pieces
  // of the second size. A piece is 0.5 ms of a gigabit: what a watcher's frame may wait behind
  // it in the link's queue.
  static constexpr size_t kPacedMessageBytes = 16 * 1024;
  static constexpr size_t kPacedPieceBytes = 64 * 1024;
  SubscriberSession(asio::io_context& io, SubscriberHub& hub, std::string transport, std::string remote);
  virtual ~SubscriberSession() = default;

  // Pipeline thread: queue a frame (newest wins) and make sure a write is under way.
  void offer(const FrameRef& frame);
  void offer_control(ControlMessage message);

  // Any thread (SubscriberHub::replace_model): the subject's model changed; on the session's io
  // thread a greeted subscriber is sent the new MeshInfo (and Model), then the new model's frames.
  void model_changed();
  // Any thread: sends a Status "refused" with `reason` (a subscriber that has not said Hello yet
  // gets it in version 1), then closes, on the session's io thread.
  void end_with(std::string reason);

  StreamKey stream_key() const { return key_.load(); }
  SubscriberMetrics stats() const;
  uint64_t id() const { return id_; }
  virtual void close() = 0;  // the session's io thread; idempotent
  // Any thread: close() now when called on the session's io thread, else posted there (after
  // whatever is already posted to it).
  void close_from_any_thread();

  // Before the session starts (the accepting thread): what admission decided. A refused
  // subscriber gets a Status saying why, in the version of its Hello (version 1 after the Hello
  // timeout), and is closed. `authenticate` (null: no token asked, or it came on the URL) checks
  // the token of the first Hello and only then admits the subscriber from `peer`: until then the
  // decision's ticket is one of the places kept for connections without the token, and the
  // Hello timeout is the short unauthenticated one (HubOptions), after which it is refused.
  void set_admission(SubscriberAdmission::Decision decision, std::shared_ptr<SubscriberAdmission> authenticate = nullptr,
                     asio::ip::address peer = {});
  // Any thread: how long the write under way has made no progress (zero when none is under way).
  std::chrono::nanoseconds write_stalled_for(std::chrono::steady_clock::time_point now) const;
  // Any thread, once: closes the subscriber whose write stalled, and counts it.
  void drop_for_write_stall(std::chrono::nanoseconds stalled);

 protected:
  // For the transports (io thread).
  void start_hello_timer(std::chrono::milliseconds timeout);
  void on_hello(const subscriber::Hello& hello);
  // A message from the subscriber (Hello or Ack) in protocol `version`; DecodeError for
  // anything else.
  void on_subscriber_message(subscriber::MessageType type, std::span<const unsigned char> payload, uint16_t version);
  void on_ack();
  // Sends a Status "refused" with the reason, then closes.
  void refuse(const std::string& reason);
  void on_protocol_error(const std::string& reason);
  void on_disconnected(const std::string& reason);
  // Writes the buffers as one protocol message, then calls write_done().
  virtual void start_write(const std::array<asio::const_buffer, 2>& buffers) = 0;
  // One piece of a message written in several (a paced joiner's MeshInfo or Model): on TCP just
  // its bytes, on WebSocket a fragment of one message (the last one with FIN). Then write_done().
  virtual void start_write_piece(asio::const_buffer piece, bool last) = 0;
  void write_done(const boost::system::error_code& ec);
  // From the transport while a write is under way: some bytes went out.
  void note_write_progress();

  asio::io_context& io_;
  SubscriberHub* hub_;  // the subject's; changes only at the first version 2 Hello, before frames flow

 private:
  void kick();
  void pump();
  // The control message in flight, from control_written_ on: the next piece (a paced joiner's
  // MeshInfo or Model) after the pacer's wait, or the rest at once.
  void write_control();
  // Version 2's first Hello: into the hub of the subject it names (SubjectDirectory); false when
  // refused (no such subject).
  bool join_subject(const std::string& subject);
  // The MeshInfo of the hub's model for `key` (and its Model for the parameter encoding) when
  // not sent yet, then frames of that model only.
  void send_model(StreamKey key);

  uint64_t id_;
  std::string transport_, remote_;
  SubscriberQueue queue_;
  asio::steady_timer hello_timer_;
  bool greeted_ = false;  // Hello received or timed out
  bool closed_ = false;
  bool writing_ = false;
  bool close_after_write_ = false;  // refused: close once the Status is written
  bool paced_ = false;  // Hello asked for kWantPaced
  bool packed_ = false;   // version 2's Hello asked for kWantPacked: MeshInfo and Model go packed
  uint16_t version_ = 0;  // of the first Hello; 0 before it
  ControlMessage mesh_info_sent_;  // the last MeshInfo queued for it
  bool model_sent_ = false;
  uint32_t model_epoch_ = 0;  // of that MeshInfo: only frames of this model are sent
  int unacked_ = 0;     // Frames sent (or being sent) and not acknowledged yet
  std::atomic<bool> pump_scheduled_{false};
  std::shared_ptr<HandlerSlot> pump_slot_;  // the posted pump's memory: the pipeline thread posts it
  std::atomic<StreamKey> key_{0};
  std::atomic<uint64_t> sent_{0};
  SubscriberQueue::Item in_flight_;
  size_t control_written_ = 0;  // of in_flight_.control, by the writes started
  asio::steady_timer pace_timer_;
  std::chrono::steady_clock::time_point write_started_;  // of the frame in flight
  std::array<unsigned char, 64> frame_prefix_{};  // the frame's first bytes with this subscriber's drop count
  // steady_clock ns of the write's start or its last progress; 0 while no write is under way.
  std::atomic<int64_t> write_progress_ns_{0};
  std::atomic<bool> dropped_for_stall_{false};
  SubscriberAdmission::Ticket admission_;  // its place among the subscribers, freed when it goes
  std::string refusal_;                    // refused as it connected: said after its Hello
  std::shared_ptr<SubscriberAdmission> authenticate_;  // set until the token came
  asio::ip::address peer_;
};

}  // namespace skinstream::server
