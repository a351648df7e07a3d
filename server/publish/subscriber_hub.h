#pragma once
// Every subscriber of one subject (TCP and WebSocket): fans each published frame out to their queues
// without waiting for any of them, keeps the MeshInfo for each stream key, the Model message and
// the latest Status in each version, and says which stream keys are wanted so the pipeline
// encodes only those.

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
  // `mesh_info` describes the full mesh (its subject field names the subject); subscribers
  // without positions get it with V = F = 0.
  SubscriberHub(Metrics& metrics, const HubOptions& options, subscriber::MeshInfo mesh_info, bool has_mesh);

  const HubOptions& options() const { return options_; }
  Metrics& metrics() { return metrics_; }
  bool has_mesh() const { return has_mesh_; }
  const std::string& subject_name() const { return mesh_info_.subject; }
  // Every subject's hub, for a Hello naming one (a new subscriber starts in the first subject's
  // hub and moves to the one it names); null: this hub serves alone. Set before any subscriber.
  void set_directory(const SubjectDirectory* directory) { directory_ = directory; }
  const SubjectDirectory* directory() const { return directory_; }

  // `accepted`: a new connection (counted); false for one moving in from another subject's hub.
  void add(const std::shared_ptr<SubscriberSession>& session, bool accepted = true);
  // Called by activate() on the subscriber's thread before its stream key becomes wanted, so
  // the pipeline can make that key's buffers there (Pipeline::prepare_encoding). Set before any
  // subscriber connects.
  void set_encoding_preparer(std::function<void(StreamKey key)> prepare) { prepare_encoding_ = std::move(prepare); }
  // After Hello (or its timeout): the session starts receiving frames of this stream key.
  void activate(SubscriberSession& session, StreamKey key);
  void remove(SubscriberSession& session);
  void close_all();

  ControlMessage mesh_info_message(StreamKey key);
  // The compressed encoding's vertex order, sent in its MeshInfo. Set before any subscriber connects.
  void set_compressed_order(std::vector<uint32_t> order) { compressed_order_ = std::move(order); }
  // The Model message of the parameter encoding (null without a mesh). Set before any
  // subscriber connects.
  void set_model_message(ControlMessage model) { model_message_ = std::move(model); }
  const ControlMessage& model_message() const { return model_message_; }
  // The latest Status, in the key's version (and with the encoding it serves).
  ControlMessage status_message(StreamKey key) const;
  // The latest Status with another detail (a notice to one subscriber, e.g. an encoding it
  // asked for and does not get), in the key's version.
  ControlMessage status_message(StreamKey key, const std::string& detail, subscriber::SourceStateCode state) const;
  void set_source_rate(float rate_hz);
  // Encodes and sends a Status to every greeted subscriber, each in its version.
  void broadcast_status(const subscriber::Status& status);

  StreamKeySet wanted_encodings() const override {
    StreamKeySet set;
    set.bits = {wanted_[0].load(std::memory_order_relaxed), wanted_[1].load(std::memory_order_relaxed)};
    return set;
  }
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
  std::array<ControlMessage, kStreamKeys> mesh_info_messages_;
  ControlMessage model_message_;
  std::vector<uint32_t> compressed_order_;
  mutable std::mutex mutex_;  // the sessions and the status
  std::vector<std::shared_ptr<SubscriberSession>> sessions_;
  std::vector<SubscriberSession*> active_;
  subscriber::Status status_;
  // The status encoded: version 1, then version 2 per encoding served.
  std::array<ControlMessage, 1 + subscriber::kEncodingCount> status_messages_;
  std::array<std::atomic<uint64_t>, 2> wanted_{};  // StreamKeySet::bits
  std::function<void(StreamKey)> prepare_encoding_;
  const SubjectDirectory* directory_ = nullptr;
};

}  // namespace skinstream::server
