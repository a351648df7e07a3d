#pragma once
// skinstreamd put together: wiring and lifecycle. The subjects (each a SubjectStream: its
// mailbox, pipeline thread, subscribers, metrics and status), the source (a recording, Vicon
// DataStream over TCP or multicast, QTM RT or NatNet) and the SubjectRouter that gives each subject its part
// of every source frame, the publishers (TCP subscriber port, HTTP port with /stream, /health, /metrics, the
// control API and static files), the take recorder, and the subjects' changes at run time (SubjectChanges:
// live calibration, swaps, subjects added and removed) and the 1 Hz Status. One io thread runs
// the source, the routing, HTTP, the WebSocket subscribers and the timers; the TCP subscribers
// are written by the publish threads.
// main.cpp adds only argument parsing and signals; tests run the same object in-process.

#include <atomic>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "server/asio.h"
#include "server/config.h"
#include "server/control/control_counters.h"
#include "server/descriptor_reserve.h"
#include "server/ingest/frame_numbering.h"
#include "server/ingest/frame_source.h"
#include "server/ingest/subject_router.h"
#include "server/logging.h"
#include "server/metrics/metrics.h"
#include "server/publish/publish_threads.h"
#include "server/publish/subject_directory.h"
#include "server/publish/subscriber_admission.h"
#include "server/record/take_recorder.h"
#include "server/subject_stream.h"
#include "server/subjects/subject_changes.h"

namespace skinstream::server {

class SubscriberHub;
class MulticastSender;
class HttpServer;
class Listener;

class Daemon : private SourceSink, private SubjectRouter::Observer, private SubjectChanges::Host {
 public:
  // Loads the subjects, opens the source file, binds both ports. Throws with a one-line message
  // (FileError, ConfigError, std::runtime_error) when any of it fails.
  explicit Daemon(const DaemonConfig& config);
  ~Daemon() override;

  void start();               // start_serving() then start_source()
  void start_serving();       // the io thread, the pipelines, both ports
  void start_source();        // frames begin to flow
  void request_stop();        // from any thread (signal handler, test)
  void wait();                // until stopped
  void stop();                // request_stop() + wait()

  int http_port() const;
  int sub_port() const;
  asio::io_context& io() { return io_; }
  // The source's own counters: its frames, its bad input (each subject has its own metrics).
  Metrics& source_metrics() { return source_metrics_; }
  // The io thread (or before start): subjects are added and removed at run time on it.
  int subject_count() const { return static_cast<int>(subjects_.size()); }
  SubjectStream& subject(int index) { return *subjects_[static_cast<size_t>(index)]; }
  SourceState source_state() const;
  std::string health_json() const;
  std::string metrics_text() const;

 private:
  // SourceSink (called on the io thread by the source).
  void on_frame(const SourceFrame& frame) override;
  void on_source_state(SourceState state, std::string_view detail) override;
  void on_bad_input(std::string_view what, std::string_view detail) override;
  // SubjectRouter::Observer (io thread, from on_frame).
  void on_match(int target, bool present, std::string_view detail) override;
  void on_unknown_subjects(std::span<const std::string> names, size_t not_listed) override;
  void on_unknown_labels(int target, std::span<const std::string> names, size_t not_listed) override;

  // SubjectChanges::Host (a subject swapped at run time).
  bool run_on_io_thread(const std::function<void()>& job) override;
  void retarget(SubjectStream& subject) override;
  double source_rate_hz() const override;
  std::unique_ptr<SubjectStream> make_subject(const std::string& name, const std::string& file) override;
  void insert_subject(std::unique_ptr<SubjectStream> subject) override;
  ControlAnswer remove_subject(const std::string& name, const std::string& who) override;
  // The io thread, every Status tick: frees removed subjects once no subscriber holds their frames.
  void free_removed_subjects();

  void broadcast_status();
  void schedule_status();
  void schedule_status_log();
  void write_ports_file() const;
  void start_recorder();
  // The io thread, each frame (record_with_source): a take while the capture system records.
  void follow_capture_recording(CaptureRecording recording);

  DaemonConfig config_;
  std::vector<int> deform_cpus_;  // deform_threads per subject, subject after subject, or none (not pinned)
  Metrics source_metrics_;
  RateLimitedLog bad_input_log_;
  RateLimitedLog state_log_;  // the source's changes of state
  SubjectDirectory directory_;  // the subjects' hubs by name; outlives them
  // Takes (when record_dir is set): its taps are the subjects' and outlive them.
  std::unique_ptr<TakeRecorder> recorder_;
  CaptureRecording capture_recording_ = CaptureRecording::Unknown;  // io thread
  bool take_from_capture_ = false;                     // the take recording was started by the capture system
  std::shared_ptr<ControlCounters> control_counters_;  // the control API's requests; null when it is off
  // Before io_: the io_context is destroyed first, and with it the handlers still holding
  // sessions whose queues hold frames of the subjects' pipelines' pools.
  SubjectStreamOptions stream_options_;  // how every subject is made (one join pacer for all)
  std::vector<std::unique_ptr<SubjectStream>> subjects_;  // the io thread's: subjects come and go at run time
  struct RemovedSubject {
    std::unique_ptr<SubjectStream> stream;
    std::chrono::steady_clock::time_point removed;
  };
  std::vector<RemovedSubject> removed_subjects_;  // until no subscriber holds their frames
  uint32_t next_stream_id_ = 0;                   // its multicast stream id
  SubjectRouter router_;
  std::vector<MarkerFrame*> routed_;  // per subject, its mailbox slot being filled (one frame)
  FrameNumbering numbering_;  // the source's frame numbers (io thread only)
  std::shared_ptr<SubscriberAdmission> admission_;  // who may subscribe, and how many: every subject's subscribers together
  asio::io_context io_;
  // The TCP subscribers' threads: destroyed before io_ and after the listeners (declared
  // between), once every session was closed on its own thread.
  PublishThreads publish_;
  DescriptorReserve descriptor_reserve_;  // the HTTP port's, for when subscribers hold every other descriptor
  std::unique_ptr<Listener> sub_listener_;
  std::unique_ptr<HttpServer> http_;
  std::unique_ptr<FrameSource> source_;
  asio::steady_timer status_timer_;
  asio::steady_timer status_log_timer_;
  std::unique_ptr<SubjectChanges> changes_;  // its thread swaps subjects through the io thread: stopped first

  mutable std::mutex state_mutex_;
  SourceState state_ = SourceState::Connecting;
  std::string state_detail_;
  double source_rate_hz_ = 0.0;

  std::thread io_thread_;
  std::atomic<bool> started_{false}, stopping_{false};
  std::mutex stop_mutex_;
  bool stopped_ = false;
};

}  // namespace skinstream::server
