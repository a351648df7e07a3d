#include "server/publish/subscriber_session.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cstring>

#include "protocol/subscriber/subscriber_stream.h"
#include "server/logging.h"
#include "server/publish/subscriber_hub.h"

namespace skinstream::server {
namespace {
std::atomic<uint64_t> next_id{1};
// What each connection says as it comes, says Hello and goes: rate-limited, since hundreds
// connect and leave at once (a wall of renderers restarting, or a flood).
RateLimitedLog connection_log;
}  // namespace

SubscriberSession::SubscriberSession(asio::io_context& io, SubscriberHub& hub, std::string transport,
                                     std::string remote)
    : io_(io),
      hub_(&hub),
      id_(next_id.fetch_add(1)),
      transport_(std::move(transport)),
      remote_(std::move(remote)),
      queue_(hub.options().queue_frames, hub.options().frame_max_wait),
      hello_timer_(io),
      pump_slot_(std::make_shared<HandlerSlot>()),
      pace_timer_(io) {}

void SubscriberSession::offer(const FrameRef& frame) {
  if (!frame->has(key_.load())) return;  // encoding not ready in this frame (wants just changed)
  queue_.push_frame(frame);
  kick();
}

void SubscriberSession::offer_control(ControlMessage message) {
  queue_.push_control(std::move(message));
  kick();
}

void SubscriberSession::close_from_any_thread() {
  if (io_.get_executor().running_in_this_thread()) close();
  else asio::post(io_, [self = shared_from_this()] { self->close(); });
}

void SubscriberSession::set_admission(SubscriberAdmission::Decision decision, std::shared_ptr<SubscriberAdmission> authenticate,
                                      asio::ip::address peer) {
  admission_ = std::move(decision.ticket);
  refusal_ = std::move(decision.reason);
  authenticate_ = std::move(authenticate);
  peer_ = peer;
}

std::chrono::nanoseconds SubscriberSession::write_stalled_for(std::chrono::steady_clock::time_point now) const {
  const int64_t since = write_progress_ns_.load(std::memory_order_relaxed);
  if (since == 0) return std::chrono::nanoseconds(0);
  return std::max(std::chrono::nanoseconds(0), now.time_since_epoch() - std::chrono::nanoseconds(since));
}

void SubscriberSession::drop_for_write_stall(std::chrono::nanoseconds stalled) {
  if (dropped_for_stall_.exchange(true)) return;
  hub_->metrics().subscribers_dropped_write_stall.fetch_add(1, std::memory_order_relaxed);
  spdlog::warn("subscriber {} ({} {}): a write made no progress for {:.1f} s; closing", id_, transport_, remote_,
               std::chrono::duration<double>(stalled).count());
  close_from_any_thread();
}

void SubscriberSession::note_write_progress() {
  write_progress_ns_.store(std::chrono::steady_clock::now().time_since_epoch().count(), std::memory_order_relaxed);
}

SubscriberMetrics SubscriberSession::stats() const {
  return {id_, transport_, remote_, sent_.load(), queue_.frames_dropped()};
}

void SubscriberSession::start_hello_timer(std::chrono::milliseconds timeout) {
  // A connection that is to give a token, or was refused, is not kept waiting long.
  const bool unauthenticated = authenticate_ || !refusal_.empty();
  if (unauthenticated) timeout = std::min(timeout, hub_->options().unauthenticated_hello_timeout);
  hello_timer_.expires_after(timeout);
  hello_timer_.async_wait([self = shared_from_this(), unauthenticated, timeout](const boost::system::error_code& ec) {
    if (ec || self->greeted_ || self->closed_) return;
    if (unauthenticated && self->refusal_.empty()) {
      self->refusal_ = "no Hello with the token within " + std::to_string(timeout.count()) + " ms";
      self->authenticate_.reset();
    } else if (!unauthenticated) {
      connection_log.info("subscriber_no_hello", fmt::format("subscriber {} ({} {}): no Hello within the timeout, sending positions only",
                                                             self->id_, self->transport_, self->remote_));
    }
    self->on_hello(subscriber::Hello{});
  });
}

void SubscriberSession::on_subscriber_message(subscriber::MessageType type, std::span<const unsigned char> payload,
                                              uint16_t version) {
  if (version_ != 0 && version != version_)
    throw subscriber::DecodeError("a version " + std::to_string(version) + " message after a version " + std::to_string(version_) +
                                  " Hello");
  switch (type) {
    case subscriber::MessageType::Hello:
      on_hello(subscriber::decode_hello(payload, version));
      return;
    case subscriber::MessageType::Ack:
      subscriber::decode_ack(payload);  // checks the length
      on_ack();
      return;
    default:
      throw subscriber::DecodeError(std::string("unexpected ") + to_string(type) + " from a subscriber");
  }
}

void SubscriberSession::on_ack() {
  // An Ack for a frame sent before a paced Hello took effect has nothing to free: ignored.
  if (closed_ || !paced_ || unacked_ == 0) return;
  --unacked_;
  if (!writing_) pump();
}

void SubscriberSession::on_hello(const subscriber::Hello& hello) {
  if (closed_ || close_after_write_) return;
  version_ = hello.version;
  if (!refusal_.empty()) return refuse(refusal_);
  if (authenticate_) {
    const std::shared_ptr<SubscriberAdmission> admission = std::move(authenticate_);  // a later Hello changes what it wants, not who it is
    if (!admission->token_matches(hello.token)) {
      return refuse(hello.token.empty() ? "this daemon asks for a token (Hello version 2's token field, or ?token= on the WebSocket URL)"
                                        : "wrong token");
    }
    // Only now a subscriber: its place among them instead of the one kept for connections without the token.
    SubscriberAdmission::Decision admitted = admission->admit(peer_);
    if (!admitted.ticket) return refuse(admitted.reason);
    admission_ = std::move(admitted.ticket);
  }
  paced_ = (hello.wants & subscriber::kWantPaced) != 0;
  packed_ = hello.version >= subscriber::kVersion2 && (hello.wants & subscriber::kWantPacked) != 0;
  // Version 2: the encoding asked for, or what can be served instead, and why.
  std::string notice;
  uint32_t flags = subscriber::frame_flags_for(hello.wants, hub_->has_mesh());
  if (hello.version >= subscriber::kVersion2) {
    // The first Hello chooses the subject; a later one may not name another.
    if (!greeted_ && !join_subject(hello.subject)) return;
    if (greeted_ && !hello.subject.empty() && hello.subject != hub_->subject_name()) {
      refuse("a Hello naming subject \"" + hello.subject + "\" after one naming \"" + hub_->subject_name() + "\"");
      return;
    }
    subscriber::Encoding served = subscriber::Encoding::Float;
    if (hello.encoding < subscriber::kEncodingCount) {
      served = static_cast<subscriber::Encoding>(hello.encoding);
    } else {
      notice = "encoding " + std::to_string(hello.encoding) + " is not one this daemon serves: positions in float";
    }
    const bool needs_mesh = served == subscriber::Encoding::Parameters || served == subscriber::Encoding::Compressed;
    if (needs_mesh && !hub_->has_mesh())
      notice = std::string("no ") + subscriber::to_string(served) + " encoding for a subject without a mesh: markers only";
    flags = subscriber::frame_flags_for(hello.wants, served, hub_->has_mesh());
  }
  const StreamKey key = server::stream_key(flags, hello.version);
  const bool changed = !greeted_ || key != key_.load();
  greeted_ = true;
  hello_timer_.cancel();
  if (!changed) return;
  key_.store(key);
  send_model(key);
  offer_control(hub_->status_message(key));
  if (!notice.empty()) {
    offer_control(hub_->status_message(key, notice, subscriber::SourceStateCode::Streaming));
    connection_log.info("subscriber_notice", fmt::format("subscriber {} ({} {}): {}", id_, transport_, remote_, notice));
  }
  hub_->activate(*this, key);
  connection_log.info("subscriber_hello", fmt::format("subscriber {} ({} {}): protocol {}, wants {:#x}, frame flags {:#x}", id_,
                                                      transport_, remote_, hello.version, hello.wants, flags));
}

void SubscriberSession::send_model(StreamKey key) {
  // Sent again only when what it describes changed (MeshInfo is 1.35 MB for the 53,500-vertex
  // body; a Hello that changes normals or markers must not cost that), the Model once a model.
  uint32_t epoch = 0;
  if (ControlMessage mesh_info = hub_->mesh_info_message(key, &epoch, packed_);
      mesh_info != mesh_info_sent_) {
    offer_control(mesh_info);
    mesh_info_sent_ = std::move(mesh_info);
  }
  if (epoch != model_epoch_) model_sent_ = false;
  model_epoch_ = epoch;
  if (stream_flags(key) & subscriber::kFrameParameters)
    if (ControlMessage model = hub_->model_message(packed_); model && !model_sent_) {
      offer_control(std::move(model));
      model_sent_ = true;
    }
}

void SubscriberSession::model_changed() {
  asio::post(io_, [self = shared_from_this()] {
    if (!self->greeted_ || self->closed_ || self->close_after_write_)
      return;  // a Hello to come gets the new one
    uint32_t epoch = 0;
    self->hub_->mesh_info_message(self->key_.load(), &epoch);
    if (epoch == self->model_epoch_) return;
    self->send_model(self->key_.load());
    self->offer_control(self->hub_->status_message(self->key_.load()));
  });
}

void SubscriberSession::end_with(std::string reason) {
  asio::post(io_, [self = shared_from_this(), reason = std::move(reason)] {
    if (self->closed_ || self->close_after_write_) return;
    if (self->version_ == 0)
      self->version_ = subscriber::kVersion1;  // no Hello yet: the version every subscriber reads
    self->refuse(reason);
  });
}

bool SubscriberSession::join_subject(const std::string& subject) {
  const SubjectDirectory* directory = hub_->directory();
  SubscriberHub* chosen =
      directory ? directory->find(subject) : (subject.empty() || subject == hub_->subject_name() ? hub_ : nullptr);
  if (!chosen) {
    refuse("no subject \"" + subject + "\" here (this daemon serves " +
           (directory ? directory->names() : "\"" + hub_->subject_name() + "\"") + ")");
    return false;
  }
  if (chosen != hub_) {
    std::shared_ptr<SubscriberSession> self = shared_from_this();  // the old hub held it
    hub_->remove(*this);
    hub_ = chosen;
    mesh_info_sent_ = {};  // another subject: its own MeshInfo and Model
    model_sent_ = false;
    hub_->add(self, /*accepted=*/false);
  }
  return true;
}

void SubscriberSession::refuse(const std::string& reason) {
  hub_->metrics().subscribers_refused.fetch_add(1, std::memory_order_relaxed);
  // Rate-limited: refusals come in floods (a subscriber reconnecting in a loop, too many at once).
  static RateLimitedLog refusals;
  refusals.warn("subscriber_refused", fmt::format("subscriber {} ({} {}): refused: {}", id_, transport_, remote_, reason));
  greeted_ = true;
  hello_timer_.cancel();
  // The Status goes out first; the session closes once its queue has been written.
  close_after_write_ = true;
  offer_control(hub_->status_message(server::stream_key(0, version_), reason, subscriber::SourceStateCode::Refused));
}

void SubscriberSession::on_protocol_error(const std::string& reason) {
  hub_->metrics().bad_subscriber_messages.fetch_add(1, std::memory_order_relaxed);
  // Rate-limited: a peer that is no subscriber may reconnect and send the same bytes again and again.
  static RateLimitedLog protocol_errors;
  protocol_errors.warn("subscriber_protocol_error", fmt::format("subscriber {} ({} {}): {}; closing", id_, transport_, remote_, reason));
  close();
}

void SubscriberSession::on_disconnected(const std::string& reason) {
  if (closed_) return;
  closed_ = true;
  hello_timer_.cancel();
  pace_timer_.cancel();
  connection_log.info("subscriber_gone", fmt::format("subscriber {} ({} {}) gone: {} (sent {}, dropped {})", id_, transport_, remote_,
                                                     reason, sent_.load(), queue_.frames_dropped()));
  write_progress_ns_.store(0, std::memory_order_relaxed);
  admission_.reset();
  hub_->remove(*this);
}

void SubscriberSession::kick() {
  if (pump_scheduled_.exchange(true)) return;
  // Only the posted pump clears pump_scheduled_, as it starts (asio has given its memory back by
  // then): one posted pump at a time, so its memory can be the session's slot.
  asio::post(io_, in_slot(pump_slot_, [self = shared_from_this()] {
               self->pump_scheduled_.store(false);
               self->pump();
             }));
}

// Io thread: from the posted kick, after a write, after an Ack. Anything pushed after the queue
// was found empty here comes with a kick that posts a pump (its flag is clear by now).
void SubscriberSession::pump() {
  if (writing_ || closed_) return;
  for (;;) {
    // A paced subscriber with its window full gets control messages only; its frames wait in
    // the queue, where the newest wins, and the one sent next is the newest.
    const bool window_full = paced_ && unacked_ >= subscriber::kPacedWindow;
    const auto take = window_full ? SubscriberQueue::Take::ControlOnly
                                  : (paced_ ? SubscriberQueue::Take::NewestFrame : SubscriberQueue::Take::OldestFrame);
    if (!queue_.pop(in_flight_, take)) return;
    if (in_flight_.control ||
        (in_flight_.frame->has(key_.load()) && in_flight_.frame->model_epoch == model_epoch_))
      break;
    in_flight_.frame
        .reset();  // encoded for this subscriber's previous wants, or of another model than its MeshInfo's
  }
  writing_ = true;
  note_write_progress();
  if (in_flight_.control) {
    control_written_ = 0;
    write_control();
    return;
  }
  if (paced_) ++unacked_;
  write_started_ = std::chrono::steady_clock::now();
  hub_->metrics().subscriber_queue_wait.observe_ns(
      std::chrono::duration_cast<std::chrono::nanoseconds>(write_started_ - in_flight_.frame->published).count());
  const std::span<const unsigned char> message = in_flight_.frame->message(key_.load());
  const size_t prefix = std::min(frame_prefix_.size(), message.size());
  std::memcpy(frame_prefix_.data(), message.data(), prefix);
  subscriber::patch_subscriber_dropped(std::span(frame_prefix_).first(prefix), static_cast<uint32_t>(queue_.frames_dropped()));
  start_write({asio::buffer(frame_prefix_.data(), prefix), asio::buffer(message.data() + prefix, message.size() - prefix)});
}

void SubscriberSession::write_control() {
  const std::vector<unsigned char>& message = *in_flight_.control;
  JoinPacer* pacer = hub_->options().join_pacer.get();
  const size_t left = message.size() - control_written_;
  // Statuses and the like go at once: only a joiner's large messages take the link's time.
  if (!pacer || message.size() < kPacedMessageBytes) {
    control_written_ = message.size();
    start_write({asio::buffer(message), asio::const_buffer()});
    return;
  }
  const size_t piece = std::min(left, kPacedPieceBytes);
  const std::chrono::nanoseconds wait = pacer->reserve(piece);
  const size_t at = control_written_;
  control_written_ += piece;
  const bool last = control_written_ == message.size();
  if (wait.count() <= 0) {
    note_write_progress();
    start_write_piece(asio::buffer(message.data() + at, piece), last);
    return;
  }
  // Waiting for the pacer is no stalled write (write_stalled_for: none under way).
  write_progress_ns_.store(0, std::memory_order_relaxed);
  pace_timer_.expires_after(wait);
  pace_timer_.async_wait(
      [self = shared_from_this(), this, at, piece, last](const boost::system::error_code& ec) {
        if (ec || closed_) return;
        note_write_progress();
        start_write_piece(asio::buffer(in_flight_.control->data() + at, piece), last);
      });
}

void SubscriberSession::write_done(const boost::system::error_code& ec) {
  if (!ec && in_flight_.control && control_written_ < in_flight_.control->size()) {
    write_control();  // its next piece
    return;
  }
  writing_ = false;
  write_progress_ns_.store(0, std::memory_order_relaxed);
  const bool was_frame = static_cast<bool>(in_flight_.frame);
  in_flight_.frame.reset();
  in_flight_.control.reset();
  if (ec) {
    if (ec != asio::error::operation_aborted) on_disconnected(ec.message());
    return;
  }
  if (was_frame) {
    sent_.fetch_add(1, std::memory_order_relaxed);
    hub_->metrics().subscriber_write.observe_ns(
        std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - write_started_).count());
  }
  pump();
  if (close_after_write_ && !writing_) close();  // a refused subscriber: its Status is written
}

}  // namespace skinstream::server
