#include "server/publish/subscriber_hub.h"

#include <algorithm>

#include "protocol/subscriber/packed_message.h"
#include "server/publish/subscriber_session.h"

namespace skinstream::server {

namespace {

// The encoding a stream key's frames are in.
subscriber::Encoding encoding_of(StreamKey key) {
  const uint32_t flags = stream_flags(key);
  if (flags & subscriber::kFrameParameters) return subscriber::Encoding::Parameters;
  if (flags & subscriber::kFrameCompressed) return subscriber::Encoding::Compressed;
  if (flags & subscriber::kFrameQuantised) return subscriber::Encoding::Quantised;
  return subscriber::Encoding::Float;
}

size_t status_index(StreamKey key) {
  return stream_version(key) >= subscriber::kVersion2 ? 1 + static_cast<size_t>(encoding_of(key)) : 0;
}

ControlMessage encode_status_for(subscriber::Status status, StreamKey key) {
  status.encoding = encoding_of(key);
  return std::make_shared<const std::vector<unsigned char>>(subscriber::encode_status(status, stream_version(key)));
}

}  // namespace

SubscriberHub::SubscriberHub(Metrics& metrics, const HubOptions& options, subscriber::MeshInfo mesh_info,
                             bool has_mesh)
    : metrics_(metrics),
      options_(options),
      has_mesh_(has_mesh),
      subject_(mesh_info.subject),
      mesh_info_(std::move(mesh_info)) {
  status_.subject = subject_;
  broadcast_status(status_);
}

void SubscriberHub::add(const std::shared_ptr<SubscriberSession>& session, bool accepted) {
  std::string retired;
  {
    std::lock_guard lock(mutex_);
    sessions_.push_back(session);
    if (accepted) metrics_.subscribers_connected.fetch_add(1, std::memory_order_relaxed);
    retired = retired_;
  }
  if (!retired.empty()) session->end_with(retired);
}

void SubscriberHub::retire(const std::string& reason) {
  std::vector<std::shared_ptr<SubscriberSession>> sessions;
  {
    std::lock_guard lock(mutex_);
    retired_ = reason;
    sessions = sessions_;
  }
  for (const auto& s : sessions) s->end_with(reason);
}

void SubscriberHub::activate(SubscriberSession& session, StreamKey key) {
  bool ready = true;
  EncodingPreparer preparer;  // a copy: replace_model() may change it once the lock is released
  {
    std::lock_guard lock(mutex_);
    preparer = preparer_;
    std::erase_if(waiting_, [&](const Waiting& w) { return w.session == &session; });
    const auto active = std::find(active_.begin(), active_.end(), &session);
    ready = !preparer.ready || preparer.ready(key);
    if (ready && active == active_.end()) active_.push_back(&session);
    if (!ready) {
      if (active != active_.end()) active_.erase(active);  // a new Hello asked for another key
      waiting_.push_back({&session, key});
    }
    update_wanted_locked();
  }
  if (!ready)
    preparer.request(key);
  else if (preparer.activated)
    preparer.activated(key);
}

void SubscriberHub::encoding_prepared(StreamKey key) {
  bool started = false;
  EncodingPreparer preparer;
  {
    std::lock_guard lock(mutex_);
    preparer = preparer_;
    std::erase_if(waiting_, [&](const Waiting& w) {
      if (w.key != key) return false;
      active_.push_back(w.session);
      started = true;
      return true;
    });
    if (started) update_wanted_locked();
  }
  if (started && preparer.activated) preparer.activated(key);
}

void SubscriberHub::replace_model(ModelReplacement replacement) {
  {
    std::lock_guard lock(mesh_info_mutex_);
    replacement.mesh_info.subject = subject_;
    replacement.mesh_info.source_rate_hz = mesh_info_.source_rate_hz;
    mesh_info_ = std::move(replacement.mesh_info);
    for (ControlMessage& m : mesh_info_messages_) m.reset();
    model_message_ = std::move(replacement.model);
    packed_ = std::move(replacement.packed);
    compressed_order_ = std::move(replacement.compressed_order);
    model_epoch_ = replacement.epoch;
  }
  std::vector<std::shared_ptr<SubscriberSession>> sessions;
  std::vector<StreamKey> waiting_keys;
  EncodingPreparer preparer;
  {
    std::lock_guard lock(mutex_);
    preparer_ = std::move(replacement.preparer);
    preparer = preparer_;
    sessions = sessions_;
    for (const Waiting& w : waiting_) waiting_keys.push_back(w.key);
  }
  if (preparer.request)
    for (StreamKey key : waiting_keys) preparer.request(key);
  for (const auto& s : sessions) s->model_changed();
}

void SubscriberHub::remove(SubscriberSession& session) {
  std::shared_ptr<SubscriberSession> keep;  // destroyed after the lock is released
  std::lock_guard lock(mutex_);
  active_.erase(std::remove(active_.begin(), active_.end(), &session), active_.end());
  std::erase_if(waiting_, [&](const Waiting& w) { return w.session == &session; });
  const auto it = std::find_if(sessions_.begin(), sessions_.end(), [&](const auto& s) { return s.get() == &session; });
  if (it != sessions_.end()) {
    keep = *it;
    sessions_.erase(it);
  }
  update_wanted_locked();
}

void SubscriberHub::close_all() {
  std::vector<std::shared_ptr<SubscriberSession>> sessions;
  {
    std::lock_guard lock(mutex_);
    sessions = sessions_;
  }
  for (const auto& s : sessions) s->close_from_any_thread();
}

void SubscriberHub::drop_stalled_writers(std::chrono::nanoseconds limit) {
  const auto now = std::chrono::steady_clock::now();
  std::vector<std::pair<std::shared_ptr<SubscriberSession>, std::chrono::nanoseconds>> stalled;
  {
    std::lock_guard lock(mutex_);
    for (const auto& s : sessions_)
      if (const auto for_how_long = s->write_stalled_for(now); for_how_long > limit) stalled.emplace_back(s, for_how_long);
  }
  for (const auto& [session, for_how_long] : stalled) session->drop_for_write_stall(for_how_long);
}

void SubscriberHub::update_wanted_locked() {
  StreamKeySet set;
  for (const SubscriberSession* s : active_) set.add(s->stream_key());
  wanted_[0].store(set.bits[0]);
  wanted_[1].store(set.bits[1]);
}

void SubscriberHub::set_compressed_order(std::vector<uint32_t> order) {
  std::lock_guard lock(mesh_info_mutex_);
  compressed_order_ = std::move(order);
}

void SubscriberHub::set_model_message(ControlMessage model) {
  std::lock_guard lock(mesh_info_mutex_);
  model_message_ = std::move(model);
}

ControlMessage SubscriberHub::model_message(bool packed) const {
  std::lock_guard lock(mesh_info_mutex_);
  return packed && packed_.model ? packed_.model : model_message_;
}

SubscriberHub::PackedFirstContact SubscriberHub::pack_first_contact(
    subscriber::MeshInfo info, const std::vector<uint32_t>& compressed_order,
    const ControlMessage& model) const {
  auto payload_of = [](const std::vector<unsigned char>& message) {
    return std::span<const unsigned char>(message).subspan(subscriber::kHeaderBytes);
  };
  PackedFirstContact packed;
  info.subject = subject_;
  for (uint32_t e = 0; e < subscriber::kEncodingCount; ++e) {
    info.encoding = static_cast<subscriber::Encoding>(e);
    info.compressed_order =
        info.encoding == subscriber::Encoding::Compressed ? compressed_order : std::vector<uint32_t>{};
    packed.mesh_info[e] = std::make_shared<const std::vector<unsigned char>>(
        subscriber::encode_packed(subscriber::MessageType::MeshInfo,
                                  payload_of(subscriber::encode_mesh_info(info, subscriber::kVersion2))));
  }
  if (model)
    packed.model = std::make_shared<const std::vector<unsigned char>>(
        subscriber::encode_packed(subscriber::MessageType::Model, payload_of(*model)));
  return packed;
}

void SubscriberHub::set_packed_first_contact(PackedFirstContact packed) {
  std::lock_guard lock(mesh_info_mutex_);
  packed_ = std::move(packed);
}

ControlMessage SubscriberHub::mesh_info_message(StreamKey key, uint32_t* epoch, bool packed) {
  // What MeshInfo describes: whether positions come, and in version 2 their encoding; not
  // normals, markers or pacing. Keys that differ only in those share one message, so a
  // subscriber whose new Hello changes only them is not sent the 1.35 MB again.
  const uint32_t encoding_flags = subscriber::kFrameQuantised | subscriber::kFrameCompressed | subscriber::kFrameParameters;
  const uint32_t described_flags = subscriber::kFrameNoPositions | (stream_version(key) >= subscriber::kVersion2 ? encoding_flags : 0u);
  const StreamKey described = stream_key(stream_flags(key) & described_flags, stream_version(key));
  std::lock_guard lock(mesh_info_mutex_);
  if (epoch) *epoch = model_epoch_;
  const bool positions = (stream_flags(described) & subscriber::kFrameNoPositions) == 0;
  if (packed && positions && stream_version(key) >= subscriber::kVersion2)
    if (ControlMessage message = packed_mesh_info_locked(encoding_of(described))) return message;
  ControlMessage& cached = mesh_info_messages_[described % kStreamKeys];
  if (!cached) {
    subscriber::MeshInfo info = mesh_info_;
    if (stream_flags(described) & subscriber::kFrameNoPositions) {
      info.vertex_count = 0;
      info.faces.clear();
      info.dominant_part.clear();
    }
    info.encoding = encoding_of(described);
    if (info.encoding == subscriber::Encoding::Compressed) info.compressed_order = compressed_order_;
    cached = std::make_shared<const std::vector<unsigned char>>(subscriber::encode_mesh_info(info, stream_version(key)));
  }
  return cached;
}

ControlMessage SubscriberHub::packed_mesh_info_locked(subscriber::Encoding encoding) {
  ControlMessage& message = packed_.mesh_info[static_cast<size_t>(encoding)];
  // The source rate is outside the deflated stream: a copy with the new one (0.3 MB).
  if (message && subscriber::packed_source_rate(*message) != mesh_info_.source_rate_hz) {
    auto copy = std::make_shared<std::vector<unsigned char>>(*message);
    subscriber::set_packed_source_rate(*copy, mesh_info_.source_rate_hz);
    message = std::move(copy);
  }
  return message;
}

SubscriberHub::PackedParameterJoin SubscriberHub::packed_parameter_join() {
  std::lock_guard lock(mesh_info_mutex_);
  return {packed_mesh_info_locked(subscriber::Encoding::Parameters), packed_.model, model_message_};
}

void SubscriberHub::set_source_rate(float rate_hz) {
  std::lock_guard lock(mesh_info_mutex_);
  if (mesh_info_.source_rate_hz == rate_hz) return;
  mesh_info_.source_rate_hz = rate_hz;
  for (ControlMessage& m : mesh_info_messages_) m.reset();
}

ControlMessage SubscriberHub::status_message(StreamKey key) const {
  std::lock_guard lock(mutex_);
  return status_messages_[status_index(key)];
}

ControlMessage SubscriberHub::status_message(StreamKey key, const std::string& detail, subscriber::SourceStateCode state) const {
  subscriber::Status status;
  {
    std::lock_guard lock(mutex_);
    status = status_;
  }
  status.detail = detail;
  status.state = state;
  return encode_status_for(status, key);
}

void SubscriberHub::broadcast_status(const subscriber::Status& in) {
  subscriber::Status status = in;
  if (status.subject.empty()) status.subject = subject_;
  std::array<ControlMessage, 1 + subscriber::kEncodingCount> messages;
  messages[0] = encode_status_for(status, stream_key(0, subscriber::kVersion1));
  const uint32_t encoding_flags[subscriber::kEncodingCount] = {0, subscriber::kFrameQuantised, subscriber::kFrameCompressed,
                                                              subscriber::kFrameParameters};
  for (uint32_t e = 0; e < subscriber::kEncodingCount; ++e)
    messages[1 + e] = encode_status_for(status, stream_key(encoding_flags[e], subscriber::kVersion2));
  std::lock_guard lock(mutex_);
  status_ = status;
  status_messages_ = messages;
  for (SubscriberSession* s : active_) s->offer_control(status_messages_[status_index(s->stream_key())]);
}

void SubscriberHub::publish(const FrameRef& frame) {
  std::lock_guard lock(mutex_);
  for (SubscriberSession* s : active_) s->offer(frame);
}

std::vector<SubscriberMetrics> SubscriberHub::subscriber_metrics() const {
  std::lock_guard lock(mutex_);
  std::vector<SubscriberMetrics> out;
  for (const auto& s : sessions_) out.push_back(s->stats());
  return out;
}

size_t SubscriberHub::active_count() const {
  std::lock_guard lock(mutex_);
  return active_.size();
}

size_t SubscriberHub::waiting_count() const {
  std::lock_guard lock(mutex_);
  return waiting_.size();
}

size_t SubscriberHub::subscriber_count() const {
  std::lock_guard lock(mutex_);
  return sessions_.size();
}

}  // namespace skinstream::server
