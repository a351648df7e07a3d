#pragma once
// Every subscriber of one subject (TCP and WebSocket): fans each published frame out to their
// queues without waiting for any of them, keeps the MeshInfo for each encoding slot and the
// latest Status in each version, and says which slots are wanted so the pipeline encodes only
// those. A new subscriber starts in the first subject's hub and moves to the hub of the subject
// its Hello names (SubjectDirectory) before it receives anything.

#include <array>
#include <atomic>
#include <chrono>
#include <functional>
#include <memory>
#include <mutex>
#include <string_view>
#include <vector>

#include "protocol/subscriber_stream.h"
#include "server/asio.h"
#include "server/logging.h"
#include "server/metrics/metrics.h"
#include "server/pipeline/pipeline.h"
#include "server/publish/subject_directory.h"
#include "server/publish/subscriber_queue.h"

namespace skinstream::server {

class SubscriberSession;

struct HubOptions {
  int queue_frames = 32;  // per subscriber, at most
  std::chrono::nanoseconds frame_max_wait = std::chrono::milliseconds(25);  // in a subscriber's queue
  std::chrono::milliseconds hello_timeout{2000};
};

class SubscriberHub : public FrameConsumer {
 public:
  // `mesh_info` describes the full mesh (its subject: the name subscribers know the subject
  // by); subscribers without positions get it with V = F = 0.
  SubscriberHub(Metrics& metrics, const HubOptions& options, subscriber::MeshInfo mesh_info, bool has_mesh);

  const HubOptions& options() const { return options_; }
  Metrics& metrics() { return metrics_; }
  bool has_mesh() const { return has_mesh_; }
  const std::string& subject() const { return mesh_info_.subject; }
  // Every subject's hub, for a Hello naming one; null: this hub serves alone.
  void set_directory(const SubjectDirectory* directory) { directory_ = directory; }
  const SubjectDirectory* directory() const { return directory_; }

  // `accepted`: a new connection (counted); false for one moving in from another hub.
  void add(const std::shared_ptr<SubscriberSession>& session, bool accepted = true);
  // Called by activate() on the subscriber's thread before its slot becomes wanted, so the
  // pipeline can make that slot's buffers there (Pipeline::prepare_encoding). Set before any
  // subscriber connects.
  void set_encoding_preparer(std::function<void(uint32_t slot)> prepare) { prepare_encoding_ = std::move(prepare); }
  // After Hello (or its timeout): the session starts receiving the frames of this slot
  // (encoding_slot: its frame flags in its protocol version).
  void activate(SubscriberSession& session, uint32_t slot);
  void remove(SubscriberSession& session);
  void close_all();

  ControlMessage mesh_info_message(uint32_t slot);
  ControlMessage status_message(uint32_t slot) const;  // the latest, in the slot's version
  ControlMessage status_saying(uint32_t slot, std::string_view detail) const;  // the latest, with this detail
  void log_refusal(std::string_view text);  // a subscriber refused (rate-limited: a flood logs once a second)
  void set_source_rate(float rate_hz);
  // Encodes a Status in each version once and sends it to every greeted subscriber (version 2
  // adds the subject, its presence and the encoding each subscriber is served).
  void broadcast_status(const subscriber::Status& status);

  uint32_t wanted_encodings() const override { return wanted_.load(); }
  void publish(const FrameRef& frame) override;

  std::vector<SubscriberMetrics> subscriber_metrics() const;
  size_t subscriber_count() const;

 private:
  void update_wanted_locked();
  ControlMessage status_locked(uint32_t slot) const;

  Metrics& metrics_;
  HubOptions options_;
  bool has_mesh_;
  // The MeshInfo cache has its own lock: encoding one (1.3 MB for the 53,500-vertex body, on a
  // subscriber's Hello) under mutex_ held the pipeline's publish() for 14 ms at start-up.
  std::mutex mesh_info_mutex_;
  subscriber::MeshInfo mesh_info_;
  std::array<ControlMessage, EncodedFrame::kEncodings> mesh_info_messages_;
  mutable std::mutex mutex_;  // the sessions and the status
  std::vector<std::shared_ptr<SubscriberSession>> sessions_;
  std::vector<SubscriberSession*> active_;
  // The latest Status: version 1, and version 2 for each encoding served (float, quantised).
  subscriber::Status status_;
  ControlMessage status_v1_;
  std::array<ControlMessage, 2> status_v2_;
  RateLimitedLog refusal_log_;
  std::atomic<uint32_t> wanted_{0};
  std::function<void(uint32_t)> prepare_encoding_;
  const SubjectDirectory* directory_ = nullptr;
};

}  // namespace skinstream::server
