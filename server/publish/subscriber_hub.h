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

#include "protocol/subscriber/subscriber_stream.h"
#include "server/asio.h"
#include "server/metrics/metrics.h"
#include "server/pipeline/pipeline.h"
#include "server/publish/join_pacer.h"
#include "server/publish/subject_directory.h"
#include "server/publish/subscriber_queue.h"

namespace skinstream::server {

class SubscriberSession;

struct HubOptions {
  int queue_frames = 32;  // per subscriber, at most
  std::chrono::nanoseconds frame_max_wait = std::chrono::milliseconds(25);  // in a subscriber's queue
  std::chrono::milliseconds hello_timeout{2000};
  // A connection that must give the token (or was refused as it connected) and sends no Hello
  // within this is refused and closed.
  std::chrono::milliseconds unauthenticated_hello_timeout{1000};
  // Every subject's joiners' MeshInfo and Model, paced together (null: each written at once).
  std::shared_ptr<JoinPacer> join_pacer;
};

class SubscriberHub : public FrameConsumer {
 public:
  // `mesh_info` describes the full mesh (its subject field names the subject); subscribers
  // without positions get it with V = F = 0.
  SubscriberHub(Metrics& metrics, const HubOptions& options, subscriber::MeshInfo mesh_info, bool has_mesh);

  const HubOptions& options() const { return options_; }
  Metrics& metrics() { return metrics_; }
  bool has_mesh() const { return has_mesh_; }
  const std::string& subject_name() const { return subject_; }
  // Every subject's hub, for a Hello naming one (a new subscriber starts in the first subject's
  // hub and moves to the one it names); null: this hub serves alone. Set before any subscriber.
  void set_directory(const SubjectDirectory* directory) { directory_ = directory; }
  const SubjectDirectory* directory() const { return directory_; }

  // `accepted`: a new connection (counted); false for one moving in from another subject's hub.
  void add(const std::shared_ptr<SubscriberSession>& session, bool accepted = true);
  // How a subscriber's stream key gets its pooled buffers (Pipeline): whether they are made,
  // a request to make them off the subscriber's thread (encoding_prepared() follows), and word
  // that a subscriber of the key now receives frames. Set before any subscriber connects; unset,
  // every key counts as made.
  struct EncodingPreparer {
    std::function<bool(StreamKey)> ready;
    std::function<void(StreamKey)> request;
    std::function<void(StreamKey)> activated;
  };
  void set_encoding_preparer(EncodingPreparer preparer) { preparer_ = std::move(preparer); }
  // After Hello (or its timeout): the session receives frames of this stream key from now on
  // when the key's buffers are made, else once they are (encoding_prepared()); meanwhile it
  // receives none. Never waits for them.
  void activate(SubscriberSession& session, StreamKey key);
  // Any thread (the pipeline's pool keeper): `key`'s buffers are made; the sessions waiting for
  // them start receiving frames.
  void encoding_prepared(StreamKey key);
  void remove(SubscriberSession& session);
  void close_all();
  // Any thread: the subject is no longer served (removed at run time). Every subscriber, and any
  // that still joins, is sent a Status "refused" with `reason` and closed.
  void retire(const std::string& reason);
  // Any thread (the daemon's 1 Hz timer): closes and counts each subscriber whose write has made
  // no progress for `limit`; a subscriber that stopped reading would otherwise hold its
  // socket, its queue and the frames in it for as long as it stays connected.
  void drop_stalled_writers(std::chrono::nanoseconds limit);

  // The MeshInfo for `key`, and in `epoch` the model it describes (EncodedFrame::model_epoch).
  // `packed`: the Packed one when it was packed for the key (else the plain one).
  ControlMessage mesh_info_message(StreamKey key, uint32_t* epoch = nullptr, bool packed = false);
  // The compressed encoding's vertex order, sent in its MeshInfo. Set before any subscriber connects.
  void set_compressed_order(std::vector<uint32_t> order);
  // The Model message of the parameter encoding (null without a mesh). Set before any
  // subscriber connects.
  void set_model_message(ControlMessage model);
  // `packed`: for a subscriber that reads Packed messages, the packed Model when there is one.
  ControlMessage model_message(bool packed = false) const;

  // What a joining subscriber that reads Packed messages is sent (version 2, with positions):
  // the MeshInfo of each encoding and the Model, packed once per model, off the threads that
  // write to subscribers (0.4-0.5 s for the 53,500-vertex body), so a joiner never waits for it.
  struct PackedFirstContact {
    std::array<ControlMessage, subscriber::kEncodingCount> mesh_info;
    ControlMessage model;
  };
  // Any thread: packs `info` (named after this hub's subject) and `model` for each encoding.
  PackedFirstContact pack_first_contact(subscriber::MeshInfo info,
                                        const std::vector<uint32_t>& compressed_order,
                                        const ControlMessage& model) const;
  // Set before any subscriber connects; a replacement brings its own.
  void set_packed_first_contact(PackedFirstContact packed);
  // What a version 2 subscriber of the parameter encoding that reads Packed messages is sent as
  // it joins (its packed MeshInfo, with the source rate now, and the packed Model), and the plain
  // Model, read together so that all three are of one model: the multicast offer's content.
  // Null without a mesh.
  struct PackedParameterJoin {
    ControlMessage mesh_info, model, plain_model;
  };
  PackedParameterJoin packed_parameter_join();

  // A new subject model in place of the one served (a live calibration, another subject file),
  // called between the old model's last frame and the new one's first: its MeshInfo, Model,
  // compressed order, the new pipeline's encoding preparer and the epoch its frames carry. Every
  // subscriber is sent the new MeshInfo (and Model) on its own thread, then frames of the new
  // model only; subscribers waiting for an encoding's buffers ask the new pipeline for them.
  // The subject's name and whether it has a mesh stay as they were.
  struct ModelReplacement {
    subscriber::MeshInfo mesh_info;
    ControlMessage model;
    std::vector<uint32_t> compressed_order;
    EncodingPreparer preparer;
    uint32_t epoch = 0;
    PackedFirstContact packed;  // pack_first_contact() of the above
  };
  void replace_model(ModelReplacement replacement);
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
  size_t active_count() const;  // subscribers receiving frames
  size_t waiting_count() const;  // subscribers waiting for their key's buffers

 private:
  void update_wanted_locked();
  // The packed MeshInfo of `encoding` with the source rate now (null when none was packed).
  ControlMessage packed_mesh_info_locked(subscriber::Encoding encoding);

  Metrics& metrics_;
  HubOptions options_;
  bool has_mesh_;
  const std::string subject_;  // mesh_info_.subject, which never changes (read without a lock)
  // The MeshInfo cache has its own lock: encoding one (1.3 MB for the 53,500-vertex body, on a
  // subscriber's Hello) under mutex_ held the pipeline's publish() for 14 ms at start-up.
  mutable std::mutex mesh_info_mutex_;
  subscriber::MeshInfo mesh_info_;
  std::array<ControlMessage, kStreamKeys> mesh_info_messages_;
  ControlMessage model_message_;
  PackedFirstContact packed_;
  std::vector<uint32_t> compressed_order_;
  uint32_t model_epoch_ = 0;
  mutable std::mutex mutex_;  // the sessions and the status
  std::vector<std::shared_ptr<SubscriberSession>> sessions_;
  std::vector<SubscriberSession*> active_;
  struct Waiting {
    SubscriberSession* session;
    StreamKey key;
  };
  std::vector<Waiting> waiting_;  // activated, their key's buffers not made yet
  std::string retired_;           // why the subject is no longer served; empty while it is
  subscriber::Status status_;
  // The status encoded: version 1, then version 2 per encoding served.
  std::array<ControlMessage, 1 + subscriber::kEncodingCount> status_messages_;
  std::array<std::atomic<uint64_t>, 2> wanted_{};  // StreamKeySet::bits
  EncodingPreparer preparer_;                      // under mutex_: replaced with the model
  const SubjectDirectory* directory_ = nullptr;
};

}  // namespace skinstream::server
