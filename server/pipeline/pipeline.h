#pragma once
// The pipeline thread: takes the marker frames from the mailbox in order, fills each (GapFiller,
// then the optional lookahead blend of GapEndBlender, as core/capture_filler.cpp does), fits the
// parts and, when a subscriber wants vertices, deforms the mesh (MeshDeformer over
// DeformWorkers), encodes the Frame message once for every stream key someone subscribed to
// (version, encoding, normals, markers) into a pooled buffer, and hands it to the publishers.
// Subscribers of the parameters alone cost no deformation: their frames carry the part fits.
// Allocates nothing per frame in steady state; never waits for a subscriber.

#include <atomic>
#include <chrono>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "core/deform/deformation_model.h"
#include "core/deform/evaluation_model.h"
#include "core/deform/mesh_deformer.h"
#include "core/gap_end_blender.h"
#include "core/gap_filler.h"
#include "core/subject_model.h"
#include "protocol/subscriber/compressed_vertices.h"
#include "server/logging.h"
#include "server/metrics/metrics.h"
#include "server/pipeline/deform_workers.h"
#include "server/pipeline/encoded_frame.h"
#include "server/pipeline/filled_frame_observer.h"
#include "server/pipeline/frame_mailbox.h"
#include "server/pipeline/on_demand_thread.h"
#include "server/pipeline/stream_key.h"

namespace skinstream::server {

// Where encoded frames go (the publishers).
class FrameConsumer {
 public:
  virtual ~FrameConsumer() = default;
  // The stream keys some subscriber receives.
  virtual StreamKeySet wanted_encodings() const = 0;
  // Called on the pipeline thread; must not block.
  virtual void publish(const FrameRef& frame) = 0;
};

struct PipelineOptions {
  int lookahead = 0;
  int deform_threads = 2;
  std::chrono::microseconds deform_spin_lead{0};  // DeformWorkerOptions
  std::vector<int> deform_cpus;                   // DeformWorkerOptions; index 0 the pipeline thread's
  double default_rate_hz = 120.0;
  GapFillerOptions filler;
  int compressed_key_interval =
      10;  // frames; the compressed encoding's key frames (protocol/subscriber/compressed_vertices.h)
  uint32_t model_epoch = 0;              // stamped on every frame (EncodedFrame::model_epoch)
  std::string thread_name = "pipeline";  // its deform workers: DeformWorkerOptions::thread_name
  std::string deform_thread_name = "deform";
};

class Pipeline {
 public:
  // `deformation` may be null (markers only: frames carry no positions). The models must
  // outlive the pipeline. Throws std::invalid_argument when the deformation model does not fit.
  Pipeline(const SubjectModel& model, const DeformationModel* deformation, const PipelineOptions& options,
           FrameMailbox& mailbox, FrameConsumer& consumer, Metrics& metrics);
  ~Pipeline();

  void start();
  void stop();  // joins the thread; safe to call twice
  // Before start(): who also sees each published frame's filled markers (the take recorder).
  void set_filled_observer(FilledFrameObserver* observer) { filled_observer_ = observer; }

  bool has_mesh() const { return deformer_ != nullptr; }
  uint32_t vertex_count() const { return deformer_ ? static_cast<uint32_t>(deformer_->vertex_count()) : 0; }
  uint64_t frames_published() const { return published_.load(); }
  // The static half of the parameter encoding (what the Model message sends); null without a mesh.
  const EvaluationModel* evaluation_model() const { return deformer_ ? &deformer_->evaluation_model() : nullptr; }
  // The order the compressed encoding codes the vertices in (MeshInfo sends it); empty without a mesh.
  const std::vector<uint32_t>& compressed_order() const { return compressed_order_; }
  // Any thread, before the pipeline is told anyone wants stream `key`: makes its buffers for
  // every pooled frame, so the first frames encoded that way do not allocate (and fault in
  // 640 kB each) on the pipeline thread. Waits for them, so it is for start-up; a subscriber's
  // Hello goes through request_encoding().
  void prepare_encoding(StreamKey key);
  // Any thread: whether stream key `key`'s buffers are made for every pooled frame, so a
  // subscriber of it can start at once.
  bool encoding_ready(StreamKey key) const;
  // Any thread, never waits: the pool keeper's thread makes `key`'s buffers (as
  // prepare_encoding() does), then calls the encoding-ready callback with `key` there. Making
  // them on the subscriber's io thread held every other subscriber of that thread for as long
  // as it took: 20-50 ms at a wave of Hellos in the soak (docs/measurements-log.md).
  void request_encoding(StreamKey key);
  // Before any request_encoding(): called on the pool keeper's thread as each requested key's
  // buffers are ready.
  void set_encoding_ready_callback(std::function<void(StreamKey)> ready) { encoding_ready_callback_ = std::move(ready); }
  // Any thread, once a subscriber of `key` receives frames: a compressed stream's next frame
  // becomes a key frame, so the new subscriber need not wait for one.
  void encoding_activated(StreamKey key);
  // Any thread, never waits (the daemon's 1 Hz tick): the pool keeper's thread frees the pooled
  // frames beyond the most in use at once since the last trim plus the kFreeFrames kept ahead,
  // so the frames that stalled subscribers held are freed once they leave; and frees the
  // buffers of every encoding no subscriber has wanted for kUnwantedHoldOff, so a burst of
  // Hellos asking for every combination of flags does not keep its memory for good.
  void trim_pool();
  size_t pool_frames() const { return pool_.allocated(); }
  size_t pool_frames_in_use() const { return pool_.in_use(); }
  size_t pool_frames_in_use_high_water() const { return pool_.in_use_high_water(); }
  static constexpr size_t pool_frames_kept_free() { return kFreeFrames; }
  static constexpr std::chrono::seconds unwanted_encoding_hold_off() { return kUnwantedHoldOff; }

 private:
  // A Frame message of this key: its size, or for the compressed encoding the most it can take.
  size_t message_bytes(StreamKey key) const;
  struct Released {
    uint32_t frame_number = 0;
    int64_t source_time_ns = 0;
    int64_t receive_time_ns = 0;
    int64_t capture_latency_ns = -1;
    uint16_t filled = 0;
    uint16_t relabelled = 0;
    subscriber::FrameTimecode timecode;
    bool has_timecode = false;
  };
  void run();
  void keep_pool();  // the pool keeper's job
  GapFillerOptions filler_options(double rate_hz) const;
  // Whether the filler must be rebuilt for the source's rate (0: not known).
  bool rate_changed(double source_rate_hz) const;
  void process(const MarkerFrame& frame, uint64_t generation);
  void publish(const Released& meta, std::span<const Vec3> positions, std::span<const MarkerStatus> status);
  FrameRef encode(const StreamKeySet& keys, subscriber::FrameInfo info, bool has_timecode, const subscriber::CompressedBlocks& compressed);
  void hand_over(FrameRef ref, const Released& meta, bool first);

  const SubjectModel& model_;
  PipelineOptions options_;
  FrameMailbox& mailbox_;
  FrameConsumer& consumer_;
  Metrics& metrics_;
  // Frames alive at once: the one being encoded, those queued for the subscribers (the frames
  // of the last max_wait, shared by them all) and one more for each subscriber whose write of
  // an older one is under way. A subscriber that stalls holds at most that one, so the frames in
  // use grow by at most one a frame; the pool keeps kFreeFrames free ahead of them, topped up on
  // pool_keeper_'s thread as soon as fewer are free (8 frames: 67 ms at 120 Hz to make more
  // before the pipeline would have to). Measured with 255 subscribers connecting at once and
  // never reading (they stall in their MeshInfo and hold no frame): the pool sized 2 frames a
  // subscriber as each came made 1,048 frame buffers (RSS 687 MB) on the threads that write to
  // the subscribers; this way, 48 (RSS 67 MB).
  static constexpr size_t kFreeFrames = 8;
  // Long enough that a subscriber that reconnects (a tablet on Wi-Fi) finds its buffers still
  // made; short enough that memory comes back well within a minute of a flood ending.
  static constexpr std::chrono::seconds kUnwantedHoldOff{10};
  FramePool pool_{static_cast<int>(kFreeFrames)};
  // The pool keeper's work, asked for from any thread (guarded by keeper_mutex_): keys whose
  // buffers a subscriber waits for, and whether a trim is due. Declared before the keeper, whose
  // thread uses them until it is joined.
  std::mutex keeper_mutex_;
  StreamKeySet requested_encodings_;
  bool trim_asked_ = false;
  std::function<void(StreamKey)> encoding_ready_callback_;
  OnDemandThread pool_keeper_;  // last of these: its thread starts as it is made

  // A source rate within this (relative) of the filler's is the same rate: the filler's time
  // constants do not notice 0.1%, and a source's clock must never rebuild it (a NatNet rate once
  // read from each pair of timestamps rebuilt it on every frame: 952 rebuilds in 12 s, processing
  // p99 1.5 -> 50 ms).
  static constexpr double kRateTolerance = 1e-3;
  // A source whose rate changes more often than this is broken or hostile: the filler follows it
  // at most this often (each rebuild allocates on this thread).
  static constexpr std::chrono::seconds kMinRateChangeInterval{2};
  std::optional<GapFiller> filler_;
  double filler_rate_hz_ = 0.0;
  std::chrono::steady_clock::time_point last_rate_change_{};
  GapEndBlender blender_;
  std::unique_ptr<MeshDeformer> deformer_;
  std::unique_ptr<DeformWorkers> workers_;

  std::vector<Vec3> filled_, released_positions_;
  std::vector<MarkerStatus> filled_status_, released_status_;
  std::vector<int> filled_revoked_;  // FrameOutput::revoked, for the blender
  std::vector<Released> held_;  // lookahead + 1 frames of metadata, by sequence number
  long sequence_ = 0;
  uint64_t generation_ = 0;
  bool has_generation_ = false;
  std::vector<float> marker_floats_;
  std::vector<uint8_t> marker_status_bytes_;
  std::vector<float> positions_, normals_;
  // Encoded once a frame for all the subscribers of the encoding.
  std::vector<unsigned char> parameter_block_;
  std::vector<uint32_t> compressed_order_;
  std::unique_ptr<subscriber::CompressedVertexEncoder> compressed_;
  std::vector<unsigned char> compressed_blocks_;

  RateLimitedLog non_finite_log_;
  FilledFrameObserver* filled_observer_ = nullptr;

  std::atomic<bool> running_{false};
  std::atomic<uint64_t> published_{0};
  std::thread thread_;
};

}  // namespace skinstream::server
