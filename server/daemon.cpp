#include "server/daemon.h"

#include <spdlog/fmt/ranges.h>
#include <spdlog/spdlog.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <future>
#include <nlohmann/json.hpp>

#include "protocol/files/file_error.h"
#include "protocol/printable_text.h"
#include "protocol/subscriber/datagram_authentication.h"
#include "server/control/control_token.h"
#include "server/daemon_control.h"
#include "server/http/http_server.h"
#include "server/ingest/file_replay_source.h"
#include "server/ingest/source_spec.h"
#include "server/listener.h"
#include "server/pipeline/deform_cpus.h"
#include "server/publish/multicast_sender.h"
#include "server/publish/subscriber_hub.h"
#include "server/publish/subscriber_session.h"
#include "server/publish/tcp_subscriber_handoff.h"
#include "server/subjects/subject_builder.h"
#include "server/thread_name.h"

namespace skinstream::server {
namespace {

// Each subject's deform threads' CPUs, subject after subject: `deform_threads` each.
std::vector<int> deform_cpus_of(const DaemonConfig& config) {
  if (config.subjects.empty())
    throw ConfigError("no subject file given (--subject FILE or NAME=FILE, or \"subject\" in the config)");
  const int subjects = static_cast<int>(config.subjects.size());
  try {
    return choose_deform_cpus(config.deform_cpus, config.deform_threads * subjects, allowed_cpus());
  } catch (const std::invalid_argument& e) {
    throw ConfigError(std::string("configuration: ") + e.what() +
                      (subjects > 1 ? " (deform_threads for each of the " + std::to_string(subjects) + " subjects)" : ""));
  }
}

MulticastSenderOptions multicast_options_of(const DaemonConfig& config, uint32_t stream_id);

// How every subject is served (each then gets its own thread names, CPUs and multicast stream id).
SubjectStreamOptions stream_options_of(const DaemonConfig& config) {
  SubjectStreamOptions options;
  options.max_frame_wait = std::chrono::milliseconds(config.max_frame_wait_ms);
  options.hub.queue_frames = config.subscriber_queue_frames;
  options.hub.frame_max_wait = std::chrono::milliseconds(config.max_frame_wait_ms);
  options.hub.hello_timeout = std::chrono::milliseconds(config.hello_timeout_ms);
  options.hub.unauthenticated_hello_timeout = std::chrono::milliseconds(config.unauthenticated_hello_timeout_ms);
  // One pacer for every subject's joiners: they share the link. Its burst: one piece of a message.
  if (config.subscriber_join_mbit > 0)
    options.hub.join_pacer = std::make_shared<JoinPacer>(config.subscriber_join_mbit * 1e6 / 8,
                                                         SubscriberSession::kPacedPieceBytes);
  PipelineOptions& pipeline = options.pipeline;
  pipeline.lookahead = config.lookahead;
  pipeline.deform_threads = config.deform_threads;
  pipeline.deform_spin_lead = std::chrono::microseconds(config.deform_spin_lead_us);
  pipeline.default_rate_hz = config.default_rate_hz;
  pipeline.filler.continuity_seconds = config.continuity_seconds;
  pipeline.filler.use_pca = config.use_pca;
  pipeline.compressed_key_interval = config.compressed_key_interval;
  return options;
}

std::vector<std::unique_ptr<SubjectStream>> load_subjects(const DaemonConfig& config,
                                                          const std::vector<int>& cpus,
                                                          const SubjectStreamOptions& shared) {
  SubjectStreamOptions options = shared;
  PipelineOptions& pipeline = options.pipeline;
  const bool several = config.subjects.size() > 1;
  std::vector<std::unique_ptr<SubjectStream>> subjects;
  for (size_t k = 0; k < config.subjects.size(); ++k) {
    // One subject keeps the names "pipeline" and "deform-N"; several are told apart by index.
    pipeline.thread_name = several ? "pipeline-" + std::to_string(k) : "pipeline";
    pipeline.deform_thread_name = several ? "deform-" + std::to_string(k) : "deform";
    pipeline.deform_cpus.clear();
    if (!cpus.empty()) {
      const auto first = cpus.begin() + static_cast<long>(k) * config.deform_threads;
      pipeline.deform_cpus.assign(first, first + config.deform_threads);
    }
    // Every subject's parameters to the one group, told apart by the stream id (its index).
    if (!config.multicast.empty()) options.multicast = multicast_options_of(config, static_cast<uint32_t>(k));
    subjects.push_back(std::make_unique<SubjectStream>(config.subjects[k], options));
    const SubjectStream& s = *subjects.back();
    if (pipeline.deform_cpus.empty())
      spdlog::info("subject {}: deform threads: {}, not pinned (deform_cpus \"{}\"), spin lead {} us", s.name(), config.deform_threads,
                   config.deform_cpus, config.deform_spin_lead_us);
    else
      spdlog::info("subject {}: deform threads: {} on CPUs {}, spin lead {} us", s.name(), config.deform_threads,
                   fmt::join(pipeline.deform_cpus, ","), config.deform_spin_lead_us);
  }
  return subjects;
}

std::vector<SubjectTarget> targets_of(const std::vector<std::unique_ptr<SubjectStream>>& subjects) {
  std::vector<SubjectTarget> targets;
  for (const auto& s : subjects) targets.push_back(s->target());
  return targets;
}

// A "HOST:PORT" key, for a config that may not have been through validate().
HostPort host_port_of(const std::string& flag, const std::string& text) {
  const std::optional<HostPort> parsed = parse_host_port(text);
  if (!parsed) throw ConfigError(flag + " " + text + ": expected HOST:PORT with a port of 1-65535");
  return *parsed;
}

MulticastSenderOptions multicast_options_of(const DaemonConfig& config, uint32_t stream_id) {
  const HostPort group = host_port_of("--multicast", config.multicast);
  MulticastSenderOptions options{{group.host, group.port, config.multicast_interface, config.multicast_ttl},
                                 stream_id};
  options.offer_mbit = config.multicast_offer_mbit;
  // The group is open to the LAN: what the offer carries is no longer behind the subscriber port's
  // admission. Said once, at start-up, where the operator set admission.
  if (options.offer_mbit > 0 && stream_id == 0 &&
      (!config.subscriber_token.empty() || !config.allow_subscribers.empty()))
    spdlog::warn(
        "multicast: MeshInfo and the Model are offered to {} on the LAN, where subscriber_token and "
        "allow_subscribers "
        "do not reach (as the frames there); multicast_offer_mbit 0 keeps them behind admission",
        config.multicast);
  if (!config.multicast_key_file.empty()) {
    try {
      options.key = subscriber::read_datagram_key_file(config.multicast_key_file);
    } catch (const std::runtime_error& e) {
      throw ConfigError(std::string("multicast_key_file: ") + e.what());
    }
  }
  return options;
}

SubjectChangesOptions changes_options_of(const DaemonConfig& config) {
  SubjectChangesOptions options;
  if (!config.calibration_dir.empty())
    options.dir = config.calibration_dir;
  else if (!config.record_dir.empty())
    options.dir = std::filesystem::path(config.record_dir) / "calibrations";
  else
    options.dir = std::filesystem::temp_directory_path() / "skinstream-calibrations";
  options.builder = config.subject_builder.empty() ? default_subject_builder() : config.subject_builder;
  options.mesh = config.calibration_mesh;
  options.default_rate_hz = config.default_rate_hz;
  return options;
}

AdmissionOptions admission_options_of(const DaemonConfig& config) {
  AdmissionOptions options;
  for (const std::string& text : config.allow_subscribers) {
    const std::optional<SubscriberNetwork> network = SubscriberNetwork::parse(text);
    if (!network) throw ConfigError("allow_subscribers: \"" + text + "\" is not a network such as 10.0.0.0/8");
    options.allow.push_back(*network);
  }
  options.max_total = config.max_subscribers;
  options.max_per_address = config.max_subscribers_per_address;
  options.token = config.subscriber_token;
  options.max_unauthenticated = config.max_unauthenticated_subscribers;
  options.max_unauthenticated_per_address = config.max_unauthenticated_per_address;
  return options;
}

}  // namespace

Daemon::Daemon(const DaemonConfig& config)
    : config_(config),
      deform_cpus_(deform_cpus_of(config)),
      stream_options_(stream_options_of(config)),
      subjects_(load_subjects(config, deform_cpus_, stream_options_)),
      next_stream_id_(static_cast<uint32_t>(config.subjects.size())),
      router_(targets_of(subjects_), static_cast<SubjectRouter::Observer&>(*this),
              1000.0 * config.source_max_coordinate_m),
      routed_(subjects_.size(), nullptr),
      publish_(config.publish_threads),
      status_timer_(io_),
      status_log_timer_(io_) {
  for (auto& s : subjects_) {
    directory_.add(s->name(), s->hub());
    s->hub().set_directory(&directory_);
  }
  admission_ = std::make_shared<SubscriberAdmission>(admission_options_of(config), source_metrics_);
  if (config.record_always && config.record_dir.empty())
    throw ConfigError("record_always needs record_dir (--record-dir)");
  if (config.record_with_source && config.record_dir.empty())
    throw ConfigError("record_with_source needs record_dir (--record-dir)");
  if (!config.record_dir.empty()) start_recorder();
  std::vector<SubjectStream*> streams;
  for (auto& stream : subjects_) streams.push_back(stream.get());
  changes_ = std::make_unique<SubjectChanges>(changes_options_of(config), streams,
                                              static_cast<SubjectChanges::Host&>(*this), recorder_.get());
  const SourceSpec source = source_spec_of(config);
  source_ = make_source(io_, source, config, static_cast<SourceSink&>(*this));
  if (source.kind == SourceSpec::Kind::Replay) {
    const auto& replay = static_cast<const FileReplaySource&>(*source_);
    // A replay's one subject never changes: a subject that cannot follow it is an error now.
    for (int k = 0; k < subject_count(); ++k) {
      const SubjectStream& s = subject(k);
      if (!s.config().name.empty() && s.config().name != replay.subject().name)
        throw ConfigError("subject \"" + s.config().name + "\" is not in the replay " + config.replay + ", whose subject is \"" +
                          replay.subject().name + "\" (name it with --replay-subject)");
      if (router_.markers_labelled_by(k, replay.subject()) == 0)
        throw FileError(config.replay, "none of the subject's " + std::to_string(s.model().marker_count()) +
                                           " marker labels is in this capture (wrong subject file?)");
    }
  } else if (source.kind == SourceSpec::Kind::None) {
    spdlog::warn("no source configured (--replay FILE, --vicon HOST:PORT, --vicon-multicast GROUP:PORT, --qtm HOST[:PORT] "
                 "or --natnet HOST[:PORT]): serving subscribers without frames");
  }

  sub_listener_ = std::make_unique<Listener>(
      io_, config.bind_address, config.sub_port, "subscriber port",
      [this](tcp::socket socket) {
        hand_off_tcp_subscriber(std::move(socket), io_, publish_, subject(0).hub(), admission_);
      },
      ListenerOptions{config.subscriber_tcp_congestion, &source_metrics_, &descriptor_reserve_, false,
                      config.subscriber_unsent_kb * 1024});
  HttpRoutes routes;
  routes.stream_admission = admission_;
  routes.stream_hub = [this]() -> SubscriberHub& { return subject(0).hub(); };
  routes.health_json = [this] { return health_json(); };
  routes.metrics_text = [this] { return metrics_text(); };
  routes.web_root = config.web_root;
  // The operator's control API, on only with a token (docs/control-api.md).
  if (const std::optional<std::string> token = load_control_token(config)) {
    routes.control = std::make_shared<DaemonControl>(recorder_.get(), *changes_);
    routes.control_token = *token;
    control_counters_ = std::make_shared<ControlCounters>();
    routes.control_counters = control_counters_;
  }
  if (!config.web_root.empty() && !std::filesystem::is_directory(config.web_root))
    throw FileError(config.web_root, "web root is not a directory");
  // Out of descriptors, the HTTP port spends the reserve: /health answers while subscribers hold the rest.
  http_ = std::make_unique<HttpServer>(
      io_, config.bind_address, config.http_port, std::move(routes),
      ListenerOptions{config.subscriber_tcp_congestion, &source_metrics_, &descriptor_reserve_, true,
                      config.subscriber_unsent_kb * 1024});
}

Daemon::~Daemon() { stop(); }

int Daemon::http_port() const { return http_->port(); }
int Daemon::sub_port() const { return sub_listener_->port(); }

SourceState Daemon::source_state() const {
  std::lock_guard lock(state_mutex_);
  return state_;
}

void Daemon::start() {
  start_serving();
  start_source();
}

void Daemon::start_source() {
  if (source_) asio::post(io_, [this] { if (!stopping_.load()) source_->start(); });
}

void Daemon::start_recorder() {
  TakeRecorderOptions options;
  options.dir = config_.record_dir;
  options.unlabelled_slots = config_.record_unlabelled;
  options.default_rate_hz = config_.default_rate_hz;
  options.config = printable(config_);
  recorder_ = std::make_unique<TakeRecorder>(std::move(options));
  for (auto& s : subjects_)
    s->set_take_tap(&recorder_->add_subject(s->name(), s->config().file, s->model().marker_names));
  for (const std::string& line : recorder_->recover_interrupted()) spdlog::warn("skinstreamd: {}", line);
  recorder_->start_thread();
}

void Daemon::follow_capture_recording(CaptureRecording recording) {
  if (recording == CaptureRecording::Unknown || recording == capture_recording_) return;
  capture_recording_ = recording;
  const std::string who = "the capture system";
  if (recording == CaptureRecording::Recording) {
    const TakeAnswer answer = recorder_->start("", who);
    take_from_capture_ = answer.status == 201;
    if (!take_from_capture_)
      spdlog::warn("skinstreamd: the capture system records, no take started: {}",
                   answer.body.value("error", ""));
  } else if (take_from_capture_) {
    recorder_->stop(who);
    take_from_capture_ = false;
  }
}

void Daemon::start_serving() {
  if (started_.exchange(true)) return;
  for (auto& s : subjects_) s->start();
  publish_.start();
  sub_listener_->start();
  http_->start();
  schedule_status();
  if (config_.status_log_seconds > 0) schedule_status_log();
  if (recorder_ && config_.record_always) {
    const TakeAnswer answer = recorder_->start("", "record_always");
    if (answer.status >= 300) spdlog::error("skinstreamd: record_always: {}", answer.body.value("error", ""));
  }
  write_ports_file();
  for (const auto& s : subjects_)
    spdlog::info("skinstreamd: subject {} ({}, {} markers, {} vertices)", s->name(), s->config().file, s->model().marker_count(),
                 s->vertex_count());
  spdlog::info("skinstreamd: HTTP port {}, subscriber port {}", http_port(), sub_port());
  io_thread_ = std::thread([this] {
    name_this_thread("io");
    auto guard = asio::make_work_guard(io_);
    io_.run();
  });
}

void Daemon::request_stop() {
  if (stopping_.exchange(true)) return;
  asio::post(io_, [this] {
    spdlog::info("skinstreamd: stopping");
    if (source_) source_->stop();
    sub_listener_->stop();
    http_->stop();
    status_timer_.cancel();
    status_log_timer_.cancel();
    for (auto& s : subjects_) s->stop();  // no more frames published after this
    for (auto& s : subjects_) s->hub().close_all();  // posted to each TCP subscriber's thread
    publish_.stop();  // after those closes
    io_.stop();
  });
}

void Daemon::wait() {
  std::lock_guard lock(stop_mutex_);
  if (io_thread_.joinable()) io_thread_.join();
  publish_.join();
  if (!stopped_) {
    stopped_ = true;
    changes_.reset();  // a build under way killed, a swap under way finished or abandoned
    for (auto& s : subjects_) s->stop();
    recorder_.reset();  // closes a take in progress: after the last frame was published
  }
}

void Daemon::stop() {
  if (started_.load()) request_stop();
  wait();
}

void Daemon::on_frame(const SourceFrame& frame) {
  source_metrics_.frames_received.fetch_add(1, std::memory_order_relaxed);
  if (frame.rate_hz > 0 && frame.rate_hz != source_rate_hz_) {  // only this thread writes it
    std::lock_guard lock(state_mutex_);
    source_rate_hz_ = frame.rate_hz;
  }
  if (recorder_ && config_.record_with_source) follow_capture_recording(frame.capture_recording);
  const FrameNumbering::Step step = numbering_.next(frame.frame_number, frame.rate_hz);
  if (step.skipped > 0) {
    source_metrics_.source_frames_skipped.fetch_add(step.skipped, std::memory_order_relaxed);
    bad_input_log_.warn("frames_skipped", "the source skipped " + std::to_string(step.skipped) + " frame numbers before frame " +
                                              std::to_string(frame.frame_number) + " (never delivered)");
  } else if (step.renumbered) {
    source_metrics_.source_renumberings.fetch_add(1, std::memory_order_relaxed);
  }
  for (size_t k = 0; k < subjects_.size(); ++k) routed_[k] = &subjects_[k]->writable();
  const SubjectRouter::Stats routed = router_.route(frame, routed_);
  if (routed.rejected_points > 0) {
    source_metrics_.count_bad_input("rejected_point");
    bad_input_log_.warn("rejected_point", "frame " + std::to_string(frame.frame_number) + ": " + std::to_string(routed.rejected_points) +
                                              " unlabelled points ignored (not finite)");
  }
  if (routed.implausible_points > 0) {
    source_metrics_.count_bad_input("implausible_point");
    bad_input_log_.warn("implausible_point", "frame " + std::to_string(frame.frame_number) + ": " +
                                                 std::to_string(routed.implausible_points) + " unlabelled points ignored (beyond " +
                                                 fmt::format("{:g}", config_.source_max_coordinate_m) + " m of the origin)");
  }
  for (size_t k = 0; k < subjects_.size(); ++k)
    if (router_.present(static_cast<int>(k))) {
      changes_->on_routed(*subjects_[k], *routed_[k]);
      subjects_[k]->post();
    }
}

bool Daemon::run_on_io_thread(const std::function<void()>& job) {
  auto done = std::make_shared<std::promise<bool>>();
  std::future<bool> ran = done->get_future();
  asio::post(io_, [this, job, done] {
    if (stopping_.load()) return done->set_value(false);
    job();
    done->set_value(true);
  });
  // Once the io thread has stopped, the job will never run: its copy goes with the io_context.
  while (ran.wait_for(std::chrono::milliseconds(50)) != std::future_status::ready)
    if (io_.stopped()) return false;
  return ran.get();
}

void Daemon::retarget(SubjectStream& changed) {
  for (size_t k = 0; k < subjects_.size(); ++k)
    if (subjects_[k].get() == &changed) router_.replace_target(static_cast<int>(k), changed.target());
}

std::unique_ptr<SubjectStream> Daemon::make_subject(const std::string& name, const std::string& file) {
  SubjectStreamOptions options = stream_options_;
  // Its own thread names; its deform threads not pinned (the CPUs were shared out at start).
  const std::string tag = std::to_string(next_stream_id_);
  options.pipeline.thread_name = "pipeline-" + tag;
  options.pipeline.deform_thread_name = "deform-" + tag;
  if (!config_.multicast.empty()) options.multicast = multicast_options_of(config_, next_stream_id_);
  ++next_stream_id_;
  return std::make_unique<SubjectStream>(SubjectConfig{name, file}, options);
}

void Daemon::insert_subject(std::unique_ptr<SubjectStream> added) {
  SubjectStream& s = *added;
  subjects_.push_back(std::move(added));
  routed_.push_back(nullptr);
  router_.add_target(s.target());
  directory_.add(s.name(), s.hub());
  s.hub().set_directory(&directory_);
  s.start();
  broadcast_status();
}

ControlAnswer Daemon::remove_subject(const std::string& name, const std::string& who) {
  const auto it =
      std::find_if(subjects_.begin(), subjects_.end(), [&](const auto& s) { return s->name() == name; });
  if (it == subjects_.end()) return {404, {{"error", "no subject " + quoted_text(name) + " here"}}};
  if (subjects_.size() == 1)
    return {409, {{"error", "subject " + name + " is the only one served: add another first"}}};
  const int k = static_cast<int>(it - subjects_.begin());
  router_.remove_target(k);
  routed_.erase(routed_.begin() + k);
  directory_.remove(name);
  std::unique_ptr<SubjectStream> removed = std::move(*it);
  subjects_.erase(it);
  removed->hub().retire("subject " + name + " was removed from this daemon");
  removed->stop();
  spdlog::info("subject {}: removed by {}; its {} subscribers were told", name, who,
               removed->hub().subscriber_count());
  removed_subjects_.push_back({std::move(removed), std::chrono::steady_clock::now()});
  return {200, {{"removed", name}}};
}

void Daemon::free_removed_subjects() {
  const auto now = std::chrono::steady_clock::now();
  std::erase_if(removed_subjects_, [&](const RemovedSubject& r) {
    return now - r.removed > std::chrono::seconds(10) && r.stream->holds_nothing();
  });
}

double Daemon::source_rate_hz() const {
  std::lock_guard lock(state_mutex_);
  return source_rate_hz_;
}

void Daemon::on_source_state(SourceState state, std::string_view detail) {
  SourceState previous;
  {
    std::lock_guard lock(state_mutex_);
    previous = state_;
    state_ = state;
    state_detail_ = std::string(detail);
  }
  // Every start of streaming (first connect, reconnect, replay loop) is a new take for the fillers.
  if (state == SourceState::Streaming) {
    numbering_.restart();
    for (auto& s : subjects_) s->new_take();
  }
  // A change of state is news; streaming again (a replay's loop) is not: the status line says
  // that the frames keep coming. At most one line a second: a source that flaps (stalls and comes
  // back, again and again) says so with a count of what was not logged.
  if (state != previous) state_log_.info("source_state", fmt::format("source: {} ({})", to_string(state), detail));
  else spdlog::debug("source: {} ({})", to_string(state), detail);
  broadcast_status();
}

void Daemon::on_bad_input(std::string_view what, std::string_view detail) {
  source_metrics_.count_bad_input(what);
  bad_input_log_.warn(what, detail);
}

void Daemon::on_match(int target, bool present, std::string_view detail) {
  subject(target).set_presence(present, detail);
  SourceState state;
  std::string source_detail;
  {
    std::lock_guard lock(state_mutex_);
    state = state_;
    source_detail = state_detail_;
  }
  subject(target).broadcast_status(state, source_detail);
}

void Daemon::on_unknown_subjects(std::span<const std::string> names, size_t not_listed) {
  for (const std::string& name : names) bad_input_log_.warn("unknown_subject", "source subject " + quoted_text(name) + " is none of ours: ignored");
  if (not_listed > 0)
    bad_input_log_.warn("unknown_subjects", std::to_string(not_listed) + " more source subjects that are none of ours (no longer listed)");
}

void Daemon::on_unknown_labels(int target, std::span<const std::string> names, size_t not_listed) {
  SubjectStream& s = subject(target);
  for (const std::string& name : names) {
    s.metrics().count_bad_input("unknown_label");
    // Rate-limited and made printable: the names come from the source, which may send thousands.
    bad_input_log_.warn("unknown_label", "subject " + s.name() + ": source label " + quoted_text(name) +
                                             " is not one of its markers: used as an unlabelled point");
  }
  if (not_listed > 0)
    bad_input_log_.warn("unknown_labels", "subject " + s.name() + ": " + std::to_string(not_listed) +
                                              " more labels that are not its markers (no longer listed)");
}

void Daemon::broadcast_status() {
  SourceState state;
  std::string detail;
  {
    std::lock_guard lock(state_mutex_);
    state = state_;
    detail = state_detail_;
  }
  for (auto& s : subjects_) s->broadcast_status(state, detail);
}

void Daemon::schedule_status() {
  status_timer_.expires_after(std::chrono::milliseconds(config_.status_interval_ms));
  status_timer_.async_wait([this](const boost::system::error_code& ec) {
    if (ec || stopping_.load()) return;
    broadcast_status();
    for (auto& s : subjects_) s->tend_subscribers(std::chrono::milliseconds(config_.subscriber_write_stall_ms));
    free_removed_subjects();
    schedule_status();
  });
}

void Daemon::schedule_status_log() {
  status_log_timer_.expires_after(std::chrono::seconds(config_.status_log_seconds));
  status_log_timer_.async_wait([this](const boost::system::error_code& ec) {
    if (ec || stopping_.load()) return;
    // The source's state at the end: a stalled or lost source shows in every line until it is back.
    const char* state = to_string(source_state());
    for (auto& s : subjects_) spdlog::info("{}; source {}", s->status_line(StatusLine::Clock::now()), state);
    schedule_status_log();
  });
}

namespace {

// The joiners' first messages as paced (null when unpaced): the rate, the bytes, how many pieces
// waited and for how long in all.
nlohmann::json join_pacing_json(const JoinPacer* pacer) {
  if (!pacer) return nullptr;
  const JoinPacer::Totals totals = pacer->totals();
  return {{"mbit", pacer->bytes_per_second() * 8 / 1e6},
          {"bytes", totals.bytes},
          {"pieces_delayed", totals.delayed},
          {"waited_seconds", totals.waited_seconds}};
}

}  // namespace

std::string Daemon::health_json() const {
  nlohmann::json source;
  {
    std::lock_guard lock(state_mutex_);
    source = {{"state", to_string(state_)}, {"detail", state_detail_}, {"rate_hz", source_rate_hz_},
              {"frames", source_metrics_.frames_received.load()},
              {"frames_skipped", source_metrics_.source_frames_skipped.load()},
              {"renumberings", source_metrics_.source_renumberings.load()}};
  }
  nlohmann::json subjects = nlohmann::json::array();
  size_t subscribers = 0;
  uint64_t dropped_write_stall = 0;
  for (const auto& s : subjects_) {
    subjects.push_back(s->health());
    subjects.back()["change"] = changes_ ? changes_->health(s->name()) : nlohmann::json();
    subscribers += subjects.back()["subscribers"].get<size_t>();
    dropped_write_stall += s->metrics().subscribers_dropped_write_stall.load();
  }
  nlohmann::json allowed = nlohmann::json::array();  // as understood: "10.1.2.3" is shown as 10.1.2.3/32
  for (const SubscriberNetwork& network : admission_->options().allow) allowed.push_back(network.to_string());
  // The first subject's figures also at the top level, where they were when a daemon had one.
  const nlohmann::json& first = subjects.front();
  const nlohmann::json health = {
      {"status", "ok"},
      {"source", source},
      {"subjects", subjects},
      {"recording", recorder_ ? recorder_->health() : nlohmann::json{{"state", "off"}}},
      {"control", control_counters_ ? control_counters_->to_json() : nlohmann::json{{"state", "off"}}},
      {"subscribers", subscribers},
      {"frame_pool", first["frame_pool"]},
      {"subscriber_limits",
       {{"max_subscribers", config_.max_subscribers},
        {"max_subscribers_per_address", config_.max_subscribers_per_address},
        {"write_stall_ms", config_.subscriber_write_stall_ms},
        {"unsent_kb", config_.subscriber_unsent_kb},
        {"allow_subscribers", allowed},
        {"token_required", admission_->token_required()},
        {"admitted", admission_->admitted()},
        {"max_unauthenticated_subscribers", config_.max_unauthenticated_subscribers},
        {"max_unauthenticated_per_address", config_.max_unauthenticated_per_address},
        {"unauthenticated", admission_->unauthenticated()},
        {"refused_unauthenticated", source_metrics_.subscribers_refused_unauthenticated.load()},
        {"refused_not_allowed", source_metrics_.subscribers_refused_not_allowed.load()},
        {"refused_limit", source_metrics_.subscribers_refused_limit.load()},
        {"refused_token", source_metrics_.subscribers_refused_token.load()},
        {"dropped_write_stall", dropped_write_stall}}},
      {"deform",
       {{"threads", config_.deform_threads},
        {"cpus", deform_cpus_},
        {"spin_lead_us", config_.deform_spin_lead_us}}},
      {"publish_threads", publish_.count()},
      {"join_pacing", join_pacing_json(subjects_.front()->hub().options().join_pacer.get())},
      {"subscriber_tcp_congestion", config_.subscriber_tcp_congestion},  // empty: the system's
      {"subject",
       {{"name", first["name"]},
        {"file", first["file"]},
        {"present", first["present"]},
        {"detail", first["detail"]},
        {"markers", first["markers"]},
        {"vertices", first["vertices"]}}},
      {"frames", first["frames"]},
      {"frame_buffers_allocated", first["frame_buffers_allocated"]},
      {"frame_buffers_allocated_by_pipeline", first["frame_buffers_allocated_by_pipeline"]},
      {"frame_buffers_released", first["frame_buffers_released"]},
      {"source_limits",
       {{"max_subjects", config_.source_max_subjects},
        {"max_markers_per_subject", config_.source_max_markers_per_subject},
        {"max_name_bytes", config_.source_max_name_bytes},
        {"max_coordinate_m", config_.source_max_coordinate_m},
        {"handshake_timeout_ms", config_.source_handshake_timeout_ms},
        {"stall_ms", config_.source_stall_ms}}},
      {"latency_ms", first["latency_ms"]}};
  return health.dump();
}

std::string Daemon::metrics_text() const {
  std::vector<SubjectMetricsView> views;
  for (const auto& s : subjects_) views.push_back({s->name(), &s->metrics(), s->hub().subscriber_metrics()});
  std::string text = render_prometheus(source_metrics_, views);
  // The sender's series carry no subject label: with several subjects they are in /health only.
  if (subjects_.size() == 1) subjects_.front()->render_multicast_metrics(text);
  if (control_counters_) control_counters_->render_metrics(text);
  return text;
}

void Daemon::write_ports_file() const {
  if (config_.ports_file.empty()) return;
  const std::string temporary = config_.ports_file + ".tmp";
  {
    std::ofstream out(temporary);
    out << nlohmann::json{{"http", http_port()}, {"sub", sub_port()}}.dump() << "\n";
    if (!out) throw FileError(config_.ports_file, "cannot write the ports file");
  }
  std::filesystem::rename(temporary, config_.ports_file);  // readers never see half a file
}

}  // namespace skinstream::server
