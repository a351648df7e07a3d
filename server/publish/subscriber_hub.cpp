#include "server/publish/subscriber_hub.h"

#include <algorithm>

#include "server/publish/subscriber_session.h"

namespace skinstream::server {

namespace {

// The encoding a version 2 subscriber of this slot is served.
subscriber::Encoding served_in(uint32_t slot) {
  return (slot_frame_flags(slot) & subscriber::kFrameQuantised) ? subscriber::Encoding::Quantised : subscriber::Encoding::Float;
}

ControlMessage message_of(std::vector<unsigned char> bytes) { return std::make_shared<const std::vector<unsigned char>>(std::move(bytes)); }

}  // namespace

SubscriberHub::SubscriberHub(Metrics& metrics, const HubOptions& options, subscriber::MeshInfo mesh_info, bool has_mesh)
    : metrics_(metrics), options_(options), has_mesh_(has_mesh), mesh_info_(std::move(mesh_info)) {
  subscriber::Status status;
  status.subject = mesh_info_.subject;
  broadcast_status(status);  // nobody to send it to yet: it becomes the latest
}

void SubscriberHub::add(const std::shared_ptr<SubscriberSession>& session, bool accepted) {
  std::lock_guard lock(mutex_);
  sessions_.push_back(session);
  if (accepted) metrics_.subscribers_connected.fetch_add(1, std::memory_order_relaxed);
}

void SubscriberHub::activate(SubscriberSession& session, uint32_t slot) {
  if (prepare_encoding_) prepare_encoding_(slot);  // does nothing once the slot is prepared
  std::lock_guard lock(mutex_);
  if (std::find(active_.begin(), active_.end(), &session) == active_.end()) active_.push_back(&session);
  update_wanted_locked();
}

void SubscriberHub::remove(SubscriberSession& session) {
  std::shared_ptr<SubscriberSession> keep;  // destroyed after the lock is released
  std::lock_guard lock(mutex_);
  active_.erase(std::remove(active_.begin(), active_.end(), &session), active_.end());
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

void SubscriberHub::update_wanted_locked() {
  uint32_t mask = 0;
  for (const SubscriberSession* s : active_) mask |= 1u << s->slot();
  wanted_.store(mask);
}

ControlMessage SubscriberHub::mesh_info_message(uint32_t slot) {
  std::lock_guard lock(mesh_info_mutex_);
  ControlMessage& cached = mesh_info_messages_[slot % mesh_info_messages_.size()];
  if (!cached) {
    subscriber::MeshInfo info = mesh_info_;
    if (slot_frame_flags(slot) & subscriber::kFrameNoPositions) {
      info.vertex_count = 0;
      info.faces.clear();
      info.dominant_part.clear();
    }
    info.encoding = served_in(slot);
    cached = message_of(subscriber::encode_mesh_info(info, slot_version(slot)));
  }
  return cached;
}

void SubscriberHub::set_source_rate(float rate_hz) {
  std::lock_guard lock(mesh_info_mutex_);
  if (mesh_info_.source_rate_hz == rate_hz) return;
  mesh_info_.source_rate_hz = rate_hz;
  for (ControlMessage& m : mesh_info_messages_) m.reset();
}

ControlMessage SubscriberHub::status_message(uint32_t slot) const {
  std::lock_guard lock(mutex_);
  return status_locked(slot);
}

ControlMessage SubscriberHub::status_locked(uint32_t slot) const {
  return slot_version(slot) >= 2 ? status_v2_[static_cast<size_t>(served_in(slot))] : status_v1_;
}

ControlMessage SubscriberHub::status_saying(uint32_t slot, std::string_view detail) const {
  subscriber::Status status;
  {
    std::lock_guard lock(mutex_);
    status = status_;
  }
  status.detail = std::string(detail);
  status.encoding = served_in(slot);
  return message_of(subscriber::encode_status(status, slot_version(slot)));
}

void SubscriberHub::log_refusal(std::string_view text) { refusal_log_.warn("subscriber_refused", text); }

void SubscriberHub::broadcast_status(const subscriber::Status& status) {
  subscriber::Status v2 = status;
  v2.subject = mesh_info_.subject;
  std::array<ControlMessage, 2> by_encoding;
  for (subscriber::Encoding encoding : {subscriber::Encoding::Float, subscriber::Encoding::Quantised}) {
    v2.encoding = encoding;
    by_encoding[static_cast<size_t>(encoding)] = message_of(subscriber::encode_status(v2, subscriber::kVersion2));
  }
  const ControlMessage v1 = message_of(subscriber::encode_status(status, subscriber::kVersion1));
  std::lock_guard lock(mutex_);
  status_ = v2;
  status_v1_ = v1;
  status_v2_ = by_encoding;
  for (SubscriberSession* s : active_) s->offer_control(status_locked(s->slot()));
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

size_t SubscriberHub::subscriber_count() const {
  std::lock_guard lock(mutex_);
  return sessions_.size();
}

}  // namespace skinstream::server
