#pragma once
// skinstreamd put together: the subject, the source (file replay or Vicon), the mailbox, the
// pipeline thread, the publishers (TCP subscriber port, HTTP port with /stream, /health,
// /metrics and static files) and the 1 Hz Status. One io thread runs the source, HTTP, the
// WebSocket subscribers and the timers; the TCP subscribers are written by the publish threads.
// main.cpp adds only argument parsing and signals; tests run the same object in-process.

#include <atomic>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "protocol/subject_file.h"
#include "server/asio.h"
#include "server/config.h"
#include "server/descriptor_reserve.h"
#include "server/ingest/frame_source.h"
#include "server/ingest/subject_router.h"
#include "server/logging.h"
#include "server/metrics/metrics.h"
#include "server/pipeline/frame_mailbox.h"
#include "server/pipeline/pipeline.h"
#include "server/publish/publish_threads.h"
#include "server/publish/subscriber_admission.h"

namespace skinstream::server {

class SubscriberHub;
class HttpServer;
class Listener;

class Daemon : private SourceSink, private SubjectRouter::Observer {
 public:
  // Loads the subject, opens the source file, binds both ports. Throws with a one-line message
  // (FileError, ConfigError, std::runtime_error) when any of it fails.
  explicit Daemon(const DaemonConfig& config);
  ~Daemon() override;

  void start();               // start_serving() then start_source()
  void start_serving();       // the io thread, the pipeline, both ports
  void start_source();        // frames begin to flow
  void request_stop();        // from any thread (signal handler, test)
  void wait();                // until stopped
  void stop();                // request_stop() + wait()

  int http_port() const;
  int sub_port() const;
  asio::io_context& io() { return io_; }
  Metrics& metrics() { return metrics_; }
  SubscriberHub& hub() { return *hub_; }
  SourceState source_state() const;
  std::string health_json() const;

 private:
  // SourceSink (called on the io thread by the source).
  void on_frame(const SourceFrame& frame) override;
  void on_source_state(SourceState state, std::string_view detail) override;
  void on_bad_input(std::string_view what, std::string_view detail) override;
  // SubjectRouter::Observer (io thread, from on_frame).
  void on_match(int target, bool present, std::string_view detail) override;
  void on_unknown_subjects(std::span<const std::string> names, size_t not_listed) override;
  void on_unknown_labels(int target, std::span<const std::string> names, size_t not_listed) override;
  void on_rejected_points(uint32_t frame_number, int count);

  void broadcast_status();
  void schedule_status();
  void write_ports_file() const;

  DaemonConfig config_;
  std::vector<int> deform_cpus_;  // one per deform thread, or none (not pinned)
  SubjectFile subject_;
  Metrics metrics_;
  RateLimitedLog bad_input_log_;
  RateLimitedLog drop_log_;  // frames that gave way in the mailbox, with the reason
  FrameMailbox mailbox_;
  SubjectRouter router_;
  std::unique_ptr<SubscriberHub> hub_;
  std::shared_ptr<SubscriberAdmission> admission_;  // who may subscribe, and how many
  std::unique_ptr<Pipeline> pipeline_;
  // After the pipeline and the hub: the io_context is destroyed first, and with it the handlers
  // still holding sessions whose queues hold frames of the pipeline's pool.
  asio::io_context io_;
  // The TCP subscribers' threads: destroyed before io_ and after the listeners (declared
  // between), once every session was closed on its own thread.
  PublishThreads publish_;
  DescriptorReserve descriptor_reserve_;  // the HTTP port's, for when subscribers hold every other descriptor
  std::unique_ptr<Listener> sub_listener_;
  std::unique_ptr<HttpServer> http_;
  std::unique_ptr<FrameSource> source_;
  asio::steady_timer status_timer_;

  mutable std::mutex state_mutex_;
  SourceState state_ = SourceState::Connecting;
  std::string state_detail_;
  double source_rate_hz_ = 0.0;
  uint64_t generation_ = 0;  // bumped when the source (re)starts streaming

  std::thread io_thread_;
  std::atomic<bool> started_{false}, stopping_{false};
  std::mutex stop_mutex_;
  bool stopped_ = false;
};

}  // namespace skinstream::server
