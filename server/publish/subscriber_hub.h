#pragma once
// Every connected subscriber (TCP and WebSocket): fans each published frame out to their queues
// without waiting for any of them, keeps the MeshInfo for each encoding and the latest Status,
// and says which frame encodings are wanted so the pipeline encodes only those.

#include <array>
#include <atomic>
#include <chrono>
#include <functional>
#include <memory>
#include <mutex>
#include <vector>

#include "protocol/subscriber_stream.h"
#include "server/asio.h"
#include "server/metrics/metrics.h"
#include "server/pipeline/pipeline.h"
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
  // `mesh_info` describes the full mesh; subscribers without positions get it with V = F = 0.
  SubscriberHub(Metrics& metrics, const HubOptions& options, subscriber::MeshInfo mesh_info, bool has_mesh);

  const HubOptions& options() const { return options_; }
  Metrics& metrics() { return metrics_; }
  bool has_mesh() const { return has_mesh_; }

  void add(const std::shared_ptr<SubscriberSession>& session);
  // Called by activate() on the subscriber's thread before its encoding becomes wanted, so the
  // pipeline can make that encoding's buffers there (Pipeline::prepare_encoding). Set before
  // any subscriber connects.
  void set_encoding_preparer(std::function<void(uint32_t frame_flags)> prepare) { prepare_encoding_ = std::move(prepare); }
  // After Hello (or its timeout): the session starts receiving frames with these flags.
  void activate(SubscriberSession& session, uint32_t frame_flags);
  void remove(SubscriberSession& session);
  void close_all();

  ControlMessage mesh_info_message(uint32_t frame_flags);
  ControlMessage status_message() const;
  void set_source_rate(float rate_hz);
  // Encodes and sends a Status to every greeted subscriber.
  void broadcast_status(const subscriber::Status& status);

  uint32_t wanted_encodings() const override { return wanted_.load(); }
  void publish(const FrameRef& frame) override;

  std::vector<SubscriberMetrics> subscriber_metrics() const;
  size_t subscriber_count() const;

 private:
  void update_wanted_locked();

  Metrics& metrics_;
  HubOptions options_;
  bool has_mesh_;
  // The MeshInfo cache has its own lock: encoding one (1.3 MB for the 53,500-vertex body, on a
  // subscriber's Hello) under mutex_ held the pipeline's publish() for 14 ms at start-up.
  std::mutex mesh_info_mutex_;
  subscriber::MeshInfo mesh_info_;
  std::array<ControlMessage, 16> mesh_info_messages_;
  mutable std::mutex mutex_;  // the sessions and the status
  std::vector<std::shared_ptr<SubscriberSession>> sessions_;
  std::vector<SubscriberSession*> active_;
  ControlMessage status_;
  std::atomic<uint32_t> wanted_{0};
  std::function<void(uint32_t)> prepare_encoding_;
};

}  // namespace skinstream::server
