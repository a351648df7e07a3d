#pragma once
// One subject the daemon serves and everything that is its own: the subject file, the mailbox
// (its bounded, newest-wins hand-off from the io thread), the Pipeline thread (fill, deformation,
// encoding) with its deform workers, the SubscriberHub (the subscribers who chose it), its
// metrics and its status. The daemon routes each source frame to the streams of the subjects
// present in it; a stream's work never waits for another's (each has its own threads: see
// SubjectStreamOptions::pipeline for how the CPUs are shared).

#include <atomic>
#include <chrono>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>

#include <nlohmann/json_fwd.hpp>

#include "protocol/files/subject_file.h"
#include "server/config.h"
#include "server/ingest/source_frame.h"
#include "server/ingest/subject_router.h"
#include "server/logging.h"
#include "server/metrics/metrics.h"
#include "server/metrics/rate_sampler.h"
#include "server/metrics/status_line.h"
#include "server/pipeline/frame_mailbox.h"
#include "server/pipeline/pipeline.h"
#include "server/publish/multicast_offer.h"
#include "server/publish/multicast_sender.h"
#include "server/publish/subscriber_hub.h"
#include "server/record/take_tap.h"

namespace skinstream::server {

struct SubjectStreamOptions {
  PipelineOptions pipeline;  // deform_cpus: this subject's share (none, or one per deform thread)
  HubOptions hub;
  std::chrono::milliseconds max_frame_wait{25};
  std::optional<MulticastSenderOptions> multicast;  // also every frame's parameters to a multicast group
};

class SubjectStream {
 public:
  // Loads the subject file. Throws FileError naming it when it cannot, or when its deformation
  // model does not fit.
  SubjectStream(SubjectConfig config, const SubjectStreamOptions& options);
  ~SubjectStream();
  SubjectStream(const SubjectStream&) = delete;
  SubjectStream& operator=(const SubjectStream&) = delete;

  // What subscribers, the log, /health and /metrics call it: the source subject it follows,
  // else its file's stem.
  const std::string& name() const { return name_; }
  // The subject file served now (a swap changes it).
  SubjectConfig config() const;
  // The io thread: the model whose frames it routes.
  const SubjectModel& model() const;
  SubjectTarget target() const { return {config_.name, model().marker_names}; }
  uint32_t vertex_count() const;
  bool has_mesh() const { return hub_->has_mesh(); }
  SubscriberHub& hub() { return *hub_; }
  Metrics& metrics() { return metrics_; }
  const Metrics& metrics() const { return metrics_; }

  // Before start(): the take recorder's tap for this subject (received and published frames).
  void set_take_tap(TakeTap* tap);
  void start();  // the pipeline thread
  void stop();   // no frame is published after it returns; safe to call twice

  // A swap of the subject (a live calibration, another file), in three steps, so that the
  // subscribers carry on across it and the io thread never waits for a file or a thread.
  // 1. Any thread but the io thread (slow: reads the file, builds the deformer): `file` read and
  //    checked as at start-up and made into a pipeline that is not started. Throws FileError with
  //    the reason; nothing served changes.
  struct Replacement;
  std::shared_ptr<Replacement> prepare_replacement(const std::string& file);
  static const SubjectModel& model_of(const Replacement& replacement);
  // 2. The io thread, between two frames: the replacement's mailbox takes this subject's frames
  //    from the next one on (the router is told the new target by the caller).
  void switch_input(Replacement& replacement);
  // 3. Off the io thread, after 2: the old pipeline publishes its last frame and stops, the
  //    subscribers are sent the new MeshInfo and Model, the new pipeline starts. The old model
  //    is freed once no subscriber holds its frames.
  void complete_replacement(std::shared_ptr<Replacement> replacement);

  // The io thread, for each frame the router gives this subject: fill writable(), then post().
  MarkerFrame& writable();
  void post();
  // The io thread: the source (re)started streaming, a new take for the filler.
  void new_take() { ++generation_; }
  // The io thread: the router's verdict on this subject (logged; a return is a new take).
  void set_presence(bool present, std::string_view detail);
  // Sends a Status to this subject's subscribers: the source's state, and this subject's. Called
  // about once a second, it also samples the rate of published frames /health reports.
  void broadcast_status(SourceState state, std::string_view source_detail);

  bool present() const;
  nlohmann::json health() const;  // /health's entry for this subject
  void render_multicast_metrics(std::string& out) const;  // appended to /metrics when multicast is on
  // The io thread, every Status tick: drops subscribers whose write made no progress for
  // `write_stall` (0: never), gives the frame pool back down to what the active ones need, and
  // frees replaced models no subscriber holds a frame of.
  void tend_subscribers(std::chrono::milliseconds write_stall);
  // Whether no subscriber is left and no frame of its pools is held (a removed subject may go).
  bool holds_nothing() const;
  // The io thread: the log's status line for the interval since the previous one.
  std::string status_line(StatusLine::Clock::time_point now);

 private:
  // The pipeline for `subject` (its models in `body`), publishing to consumer_.
  void make_pipeline(Replacement& body, uint32_t epoch);
  // The body's MeshInfo and Model packed for joiners (SubscriberHub::PackedFirstContact).
  void pack_first_contact(Replacement& body);
  std::shared_ptr<Replacement> served() const;

  SubjectConfig config_;  // its file: under mutex_ (a swap changes it)
  std::string name_;
  SubjectStreamOptions options_;
  Metrics metrics_;
  RateLimitedLog bad_input_log_;
  RateLimitedLog drop_log_;  // frames that gave way in the mailbox, with the reason
  StatusLine status_line_;
  std::unique_ptr<SubscriberHub> hub_;
  std::unique_ptr<MulticastSender> multicast_;  // the pipeline's consumer in front of the hub, when on
  std::unique_ptr<MulticastOffer> offer_;       // the packed MeshInfo and Model offered to the group, when on
  FrameConsumer* consumer_ = nullptr;           // multicast_ or hub_
  std::shared_ptr<Replacement> body_;  // the subject file, mailbox and pipeline served (under mutex_)
  Replacement* input_ = nullptr;       // whose mailbox the io thread fills: body_'s, or the next one's
  std::vector<std::shared_ptr<Replacement>>
      retired_;                          // replaced, until no subscriber holds their frames (under mutex_)
  std::atomic<uint32_t> last_epoch_{0};  // of the newest model made
  std::vector<int> deform_cpus_;
  int deform_threads_ = 0;
  TakeTap* take_tap_ = nullptr;
  uint64_t generation_ = 0;  // io thread only
  double source_rate_hz_ = 0.0;  // io thread only

  mutable std::mutex mutex_;  // what /health reads from another thread
  bool present_ = false;
  std::string presence_detail_ = "no frame from the source yet";
  // Frames published per second between the last two samples at least half a second apart.
  double published_fps_ = 0.0;
  RateSampler published_rate_;
};

}  // namespace skinstream::server
