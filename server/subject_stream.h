#pragma once
// One subject the daemon serves and everything that is its own: the subject file, the mailbox
// (its bounded, newest-wins hand-off from the io thread), the Pipeline thread (fill, deformation,
// encoding) with its deform workers, the SubscriberHub (the subscribers who chose it), its
// metrics and its status. The daemon routes each source frame to the streams of the subjects
// present in it; a stream's work never waits for another's (each has its own threads: see
// SubjectStreamOptions::pipeline for how the CPUs are shared).

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
  const SubjectConfig& config() const { return config_; }
  const SubjectModel& model() const { return subject_.model; }
  SubjectTarget target() const { return {config_.name, subject_.model.marker_names}; }
  uint32_t vertex_count() const { return pipeline_->vertex_count(); }
  SubscriberHub& hub() { return *hub_; }
  Metrics& metrics() { return metrics_; }
  const Metrics& metrics() const { return metrics_; }

  // Before start(): the take recorder's tap for this subject (received and published frames).
  void set_take_tap(TakeTap* tap);
  void start();  // the pipeline thread
  void stop();   // no frame is published after it returns; safe to call twice

  // The io thread, for each frame the router gives this subject: fill writable(), then post().
  MarkerFrame& writable() { return mailbox_.writable(); }
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
  // `write_stall` (0: never), and gives the frame pool back down to what the active ones need.
  void tend_subscribers(std::chrono::milliseconds write_stall);
  // The io thread: the log's status line for the interval since the previous one.
  std::string status_line(StatusLine::Clock::time_point now);

 private:
  SubjectConfig config_;
  std::string name_;
  SubjectFile subject_;
  Metrics metrics_;
  RateLimitedLog bad_input_log_;
  RateLimitedLog drop_log_;  // frames that gave way in the mailbox, with the reason
  StatusLine status_line_;
  FrameMailbox mailbox_;
  std::unique_ptr<SubscriberHub> hub_;
  std::unique_ptr<MulticastSender> multicast_;  // the pipeline's consumer in front of the hub, when on
  std::unique_ptr<Pipeline> pipeline_;
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
