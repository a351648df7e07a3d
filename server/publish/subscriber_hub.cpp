#include "server/publish/subscriber_hub.h"

#include <algorithm>

#include "server/publish/subscriber_session.h"

namespace skinstream::server {

SubscriberHub::SubscriberHub(Metrics& metrics, const HubOptions& options, subscriber::MeshInfo mesh_info, bool has_mesh)
    : metrics_(metrics), options_(options), has_mesh_(has_mesh), mesh_info_(std::move(mesh_info)) {
  status_ = std::make_shared<const std::vector<unsigned char>>(subscriber::encode_status({}));
}

void SubscriberHub::add(const std::shared_ptr<SubscriberSession>& session) {
  std::lock_guard lock(mutex_);
  sessions_.push_back(session);
  metrics_.subscribers_connected.fetch_add(1, std::memory_order_relaxed);
}

void SubscriberHub::activate(SubscriberSession& session, uint32_t frame_flags) {
  if (prepare_encoding_) prepare_encoding_(frame_flags);  // does nothing once the encoding is prepared
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
  for (const SubscriberSession* s : active_) mask |= 1u << s->frame_flags();
  wanted_.store(mask);
}

ControlMessage SubscriberHub::mesh_info_message(uint32_t frame_flags) {
  std::lock_guard lock(mesh_info_mutex_);
  ControlMessage& cached = mesh_info_messages_[frame_flags & 15u];
  if (!cached) {
    subscriber::MeshInfo info = mesh_info_;
    if (frame_flags & subscriber::kFrameNoPositions) {
      info.vertex_count = 0;
      info.faces.clear();
      info.dominant_part.clear();
    }
    cached = std::make_shared<const std::vector<unsigned char>>(subscriber::encode_mesh_info(info));
  }
  return cached;
}

void SubscriberHub::set_source_rate(float rate_hz) {
  std::lock_guard lock(mesh_info_mutex_);
  if (mesh_info_.source_rate_hz == rate_hz) return;
  mesh_info_.source_rate_hz = rate_hz;
  for (ControlMessage& m : mesh_info_messages_) m.reset();
}

ControlMessage SubscriberHub::status_message() const {
  std::lock_guard lock(mutex_);
  return status_;
}

void SubscriberHub::broadcast_status(const subscriber::Status& status) {
  const ControlMessage message = std::make_shared<const std::vector<unsigned char>>(subscriber::encode_status(status));
  std::lock_guard lock(mutex_);
  status_ = message;
  for (SubscriberSession* s : active_) s->offer_control(message);
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
