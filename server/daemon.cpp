#include "server/daemon.h"

#include <spdlog/fmt/ranges.h>
#include <spdlog/spdlog.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include "protocol/file_error.h"
#include "protocol/subscriber_model.h"
#include "protocol/printable_text.h"
#include "server/http/http_server.h"
#include "server/ingest/file_replay_source.h"
#include "server/ingest/natnet_source.h"
#include "server/ingest/qtm_source.h"
#include "server/ingest/vicon_multicast_source.h"
#include "server/ingest/vicon_source.h"
#include "server/listener.h"
#include "server/pipeline/deform_cpus.h"
#include "server/publish/subscriber_hub.h"
#include "server/publish/tcp_subscriber.h"
#include "server/thread_name.h"

namespace skinstream::server {
namespace {

SubjectFile load_subject(const DaemonConfig& config) {
  if (config.subject.empty()) throw ConfigError("no subject file given (--subject FILE or \"subject\" in the config)");
  return read_subject_file(config.subject);
}

subscriber::MeshInfo mesh_info_of(const SubjectFile& subject, const std::string& path) {
  subscriber::MeshInfo info;
  // The subject's name: its file's stem until subjects are named on the command line.
  info.subject = std::filesystem::path(path).stem().string();
  const SubjectModel& model = subject.model;
  info.marker_count = static_cast<uint32_t>(model.marker_count());
  info.marker_names = model.marker_names;
  for (const auto& t : model.triangles)
    info.marker_triangles.push_back({static_cast<uint32_t>(t[0]), static_cast<uint32_t>(t[1]), static_cast<uint32_t>(t[2])});
  if (subject.deformation) {
    const DeformationModel& d = *subject.deformation;
    info.vertex_count = static_cast<uint32_t>(d.vertex_count());
    info.part_count = static_cast<uint32_t>(d.part_count());
    for (const auto& f : d.faces)
      info.faces.push_back({static_cast<uint32_t>(f[0]), static_cast<uint32_t>(f[1]), static_cast<uint32_t>(f[2])});
    info.dominant_part.resize(info.vertex_count);
    for (int v = 0; v < d.vertex_count(); ++v) {
      const int p = d.dominant_part(v);
      info.dominant_part[v] = p >= 0 && p < 255 ? static_cast<uint8_t>(p) : uint8_t{255};
    }
  }
  return info;
}

// A "HOST:PORT" key, for a config that may not have been through validate().
HostPort host_port_of(const std::string& flag, const std::string& text) {
  const std::optional<HostPort> parsed = parse_host_port(text);
  if (!parsed) throw ConfigError(flag + " " + text + ": expected HOST:PORT with a port of 1-65535");
  return *parsed;
}

// A "HOST[:PORT]" key (qtm, natnet), likewise.
HostPort host_port_of(const std::string& flag, const std::string& text, uint16_t default_port) {
  const std::optional<HostPort> parsed = parse_host_with_port(text, default_port);
  if (!parsed) throw ConfigError(flag + " " + text + ": expected HOST or HOST:PORT with a port of 1-65535");
  return *parsed;
}

ViconSourceOptions vicon_options_of(const DaemonConfig& config) {
  const HostPort address = host_port_of("--vicon", config.vicon);
  ViconSourceOptions options;
  options.host = address.host;
  options.port = address.port;
  options.mode = config.vicon_pull ? ViconSourceOptions::Mode::ClientPull : ViconSourceOptions::Mode::ServerPush;
  return options;
}

vicon::DescriptionLimits description_limits_of(const DaemonConfig& config) {
  vicon::DescriptionLimits limits;
  limits.max_subjects = static_cast<uint32_t>(config.source_max_subjects);
  limits.max_markers_per_subject = static_cast<uint32_t>(config.source_max_markers_per_subject);
  limits.max_name_bytes = static_cast<uint32_t>(config.source_max_name_bytes);
  return limits;
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
  return options;
}

subscriber::SourceStateCode code_of(SourceState s) { return static_cast<subscriber::SourceStateCode>(static_cast<uint32_t>(s)); }

// The /metrics histograms condensed for scripts, over the daemon's life: per stage its count,
// the quantiles as bucket upper bounds ("le") and the largest value seen.
nlohmann::json latency_summaries(const Metrics& metrics) {
  nlohmann::json out = nlohmann::json::object();
  auto add = [&](const char* name, const LatencyHistogram& histogram) {
    const LatencyHistogram::Summary s = histogram.summary();
    out[name] = {{"count", s.count}, {"p50_le", s.p50_le_ms}, {"p99_le", s.p99_le_ms}, {"p99_9_le", s.p99_9_le_ms}, {"max", s.max_ms}};
  };
  add("receive_to_take", metrics.receive_to_take);
  add("fill", metrics.fill);
  add("deform", metrics.deform);
  add("normals", metrics.normals);
  add("encode", metrics.encode);
  add("encode_compressed", metrics.encode_compressed);
  add("receive_to_publish", metrics.receive_to_publish);
  add("subscriber_queue_wait", metrics.subscriber_queue_wait);
  add("subscriber_write", metrics.subscriber_write);
  return out;
}

}  // namespace

Daemon::Daemon(const DaemonConfig& config)
    : config_(config),
      subject_(load_subject(config)),
      mailbox_(subject_.model.marker_count(), std::chrono::milliseconds(config.max_frame_wait_ms)),
      router_({SubjectTarget{"", subject_.model.marker_names}}, static_cast<SubjectRouter::Observer&>(*this)),
      publish_(config.publish_threads),
      status_timer_(io_) {
  const SubjectModel& model = subject_.model;
  if (!subject_.deformation)
    spdlog::warn("{}: no deformation model (built without --mesh): publishing markers only (MeshInfo with V = 0)",
                 config.subject);
  HubOptions hub_options;
  hub_options.queue_frames = config.subscriber_queue_frames;
  hub_options.frame_max_wait = std::chrono::milliseconds(config.max_frame_wait_ms);
  hub_options.hello_timeout = std::chrono::milliseconds(config.hello_timeout_ms);
  hub_ = std::make_unique<SubscriberHub>(metrics_, hub_options, mesh_info_of(subject_, config.subject), subject_.deformation.has_value());
  admission_ = std::make_shared<SubscriberAdmission>(admission_options_of(config), metrics_);

  PipelineOptions pipeline_options;
  pipeline_options.lookahead = config.lookahead;
  pipeline_options.deform_threads = config.deform_threads;
  pipeline_options.deform_spin_lead = std::chrono::microseconds(config.deform_spin_lead_us);
  try {
    deform_cpus_ = pipeline_options.deform_cpus = choose_deform_cpus(config.deform_cpus, config.deform_threads, allowed_cpus());
  } catch (const std::invalid_argument& e) {
    throw ConfigError(std::string("configuration: ") + e.what());
  }
  if (pipeline_options.deform_cpus.empty())
    spdlog::info("deform threads: {}, not pinned (deform_cpus \"{}\"), spin lead {} us", config.deform_threads,
                 config.deform_cpus, config.deform_spin_lead_us);
  else
    spdlog::info("deform threads: {} on CPUs {}, spin lead {} us", config.deform_threads,
                 fmt::join(pipeline_options.deform_cpus, ","), config.deform_spin_lead_us);
  pipeline_options.default_rate_hz = config.default_rate_hz;
  pipeline_options.filler.continuity_seconds = config.continuity_seconds;
  pipeline_options.filler.use_pca = config.use_pca;
  pipeline_options.compressed_key_interval = config.compressed_key_interval;
  try {
    pipeline_ = std::make_unique<Pipeline>(model, subject_.deformation ? &*subject_.deformation : nullptr, pipeline_options,
                                           mailbox_, *hub_, metrics_);
  } catch (const std::invalid_argument& e) {
    throw FileError(config.subject, std::string("deformation model unusable: ") + e.what());
  }

  hub_->set_encoding_preparer([pipeline = pipeline_.get(), hub = hub_.get()](StreamKey key) {
    pipeline->prepare_encoding(key);
    pipeline->size_pool_for(hub->active_count() + 1);  // this one is about to be active
  });
  hub_->set_compressed_order(pipeline_->compressed_order());
  if (const EvaluationModel* evaluation = pipeline_->evaluation_model()) {
    hub_->set_model_message(std::make_shared<const std::vector<unsigned char>>(subscriber::encode_model(*evaluation)));
    spdlog::info("parameter encoding: Model message of {} bytes ({} parts, {} RBF centres, {} influences)",
                 hub_->model_message()->size(), evaluation->part_count(), evaluation->member_count(), evaluation->influence_count());
  }

  if (!config.replay.empty()) {
    auto replay = std::make_unique<FileReplaySource>(io_, config.replay, static_cast<SourceSink&>(*this),
                                                     ReplayOptions{config.loop, config.speed, {}});
    if (router_.markers_labelled_by(0, replay->subject()) == 0)
      throw FileError(config.replay, "none of the subject's " + std::to_string(model.marker_count()) +
                                         " marker labels is in this capture (wrong subject file?)");
    source_ = std::move(replay);
  } else if (!config.vicon_multicast.empty()) {
    const HostPort address = host_port_of("--vicon-multicast", config.vicon_multicast);
    ViconMulticastSourceOptions options;
    options.group = address.host;
    options.port = address.port;
    options.limits = description_limits_of(config);
    spdlog::info("source: Vicon DataStream multicast {}:{} (receive only)", options.group, options.port);
    source_ = std::make_unique<ViconMulticastSource>(io_, std::move(options), static_cast<SourceSink&>(*this));
  } else if (!config.vicon.empty()) {
    ViconSourceOptions options = vicon_options_of(config);
    spdlog::info("source: Vicon DataStream {}:{} ({})", options.host, options.port,
                 options.mode == ViconSourceOptions::Mode::ClientPull ? "client pull" : "server push");
    source_ = std::make_unique<ViconSource>(io_, std::move(options), static_cast<SourceSink&>(*this));
  } else if (!config.qtm.empty()) {
    const HostPort address = host_port_of("--qtm", config.qtm, qtm::kLittleEndianPort);
    QtmSourceOptions options;
    options.host = address.host;
    options.port = address.port;
    spdlog::info("source: QTM RT {}:{}", options.host, options.port);
    source_ = std::make_unique<QtmSource>(io_, std::move(options), static_cast<SourceSink&>(*this));
  } else if (!config.natnet.empty()) {
    const HostPort address = host_port_of("--natnet", config.natnet, natnet::kCommandPort);
    NatNetSourceOptions options;
    options.host = address.host;
    options.command_port = address.port;
    options.interface_address = config.natnet_interface;
    spdlog::info("source: NatNet {}:{}", options.host, options.command_port);
    source_ = std::make_unique<NatNetSource>(io_, std::move(options), static_cast<SourceSink&>(*this));
  } else {
    spdlog::warn("no source configured (--replay FILE, --vicon HOST:PORT, --vicon-multicast GROUP:PORT, --qtm HOST[:PORT] "
                 "or --natnet HOST[:PORT]): serving subscribers without frames");
  }

  sub_listener_ = std::make_unique<Listener>(io_, config.bind_address, config.sub_port, "subscriber port", [this](tcp::socket socket) {
    boost::system::error_code ec;
    const auto endpoint = socket.remote_endpoint(ec);
    if (ec) return;  // gone before it was taken
    const std::string remote = endpoint.address().to_string() + ":" + std::to_string(endpoint.port());
    // To the publish thread with the fewest subscribers: the socket moves to its io_context, and
    // the session starts there. (Accepting straight onto that context would leave the waiting
    // accept, and a socket of a publish context, in io_'s queue, which outlives the publish
    // threads: see the members' order in daemon.h.) Without publish threads it stays on io_.
    PublishThreads::Placement placed = publish_.place(io_);
    if (&placed.io != &io_) {
      tcp::socket own(placed.io);
      const tcp protocol = socket.local_endpoint(ec).protocol();
      const auto handle = ec ? tcp::socket::native_handle_type(-1) : socket.release(ec);
      if (!ec) {
        own.assign(protocol, handle, ec);
        if (ec) ::close(handle);
      }
      if (ec) {
        spdlog::warn("subscriber {}: cannot hand the socket to its thread: {}; closing", remote, ec.message());
        return;
      }
      socket = std::move(own);
    }
    auto subscriber = std::make_shared<TcpSubscriber>(placed.io, *hub_, std::move(socket), remote, std::move(placed.token));
    // Refused or not, the subscriber is answered after its Hello, in the version it speaks.
    SubscriberAdmission::Decision admitted = admission_->admit(endpoint.address());
    const bool ask_token = admitted.ticket && admission_->token_required();
    subscriber->set_admission(std::move(admitted), ask_token ? admission_ : nullptr);
    hub_->add(subscriber);
    asio::post(placed.io, [subscriber] { subscriber->start(); });
  }, ListenerOptions{config.subscriber_tcp_congestion, &metrics_, &descriptor_reserve_, false});
  HttpRoutes routes;
  routes.stream_admission = admission_;
  routes.health_json = [this] { return health_json(); };
  routes.metrics_text = [this] { return metrics_.render_prometheus(hub_->subscriber_metrics()); };
  routes.web_root = config.web_root;
  if (!config.web_root.empty() && !std::filesystem::is_directory(config.web_root))
    throw FileError(config.web_root, "web root is not a directory");
  // Out of descriptors, the HTTP port spends the reserve: /health answers while subscribers hold the rest.
  http_ = std::make_unique<HttpServer>(io_, config.bind_address, config.http_port, *hub_, std::move(routes),
                                       ListenerOptions{config.subscriber_tcp_congestion, &metrics_, &descriptor_reserve_, true});
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

void Daemon::start_serving() {
  if (started_.exchange(true)) return;
  pipeline_->start();
  publish_.start();
  sub_listener_->start();
  http_->start();
  schedule_status();
  write_ports_file();
  spdlog::info("skinstreamd: subject {} ({} markers, {} vertices), HTTP port {}, subscriber port {}", config_.subject,
               subject_.model.marker_count(), pipeline_->vertex_count(), http_port(), sub_port());
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
    pipeline_->stop();  // no more frames published after this
    hub_->close_all();  // posted to each TCP subscriber's thread
    publish_.stop();    // after those closes
    io_.stop();
  });
}

void Daemon::wait() {
  std::lock_guard lock(stop_mutex_);
  if (io_thread_.joinable()) io_thread_.join();
  publish_.join();
  if (!stopped_) {
    stopped_ = true;
    pipeline_->stop();
  }
}

void Daemon::stop() {
  if (started_.load()) request_stop();
  wait();
}

void Daemon::on_frame(const SourceFrame& frame) {
  metrics_.frames_received.fetch_add(1, std::memory_order_relaxed);
  MarkerFrame* const out[] = {&mailbox_.writable()};
  const SubjectRouter::Stats routed = router_.route(frame, out);
  if (routed.rejected_points > 0) on_rejected_points(frame.frame_number, routed.rejected_points);
  if (!router_.present(0)) return;
  const MarkerFrame& in = *out[0];
  if (in.rejected_points > 0) on_rejected_points(in.frame_number, in.rejected_points);
  if (in.source_rate_hz > 0 && in.source_rate_hz != source_rate_hz_) {
    {
      std::lock_guard lock(state_mutex_);
      source_rate_hz_ = in.source_rate_hz;
    }
    hub_->set_source_rate(static_cast<float>(in.source_rate_hz));
  }
  uint64_t generation;
  {
    std::lock_guard lock(state_mutex_);
    generation = generation_;
  }
  if (const std::optional<FrameMailbox::Drop> drop = mailbox_.post(generation)) {
    // Says which side fell behind: the pipeline (it took nothing for a while), or the source,
    // whose frames came in a burst longer than the mailbox holds.
    using Ms = std::chrono::duration<double, std::milli>;
    const bool full = drop->reason == FrameMailbox::DropReason::kMailboxFull;
    drop_log_.warn("frame_gave_way",
                   fmt::format("frame {} gave way to newer ones after waiting {:.1f} ms: {}; the pipeline last took a frame {:.1f} ms "
                               "before ({} dropped in all)",
                               drop->frame_number, Ms(drop->waited).count(),
                               full ? "more frames arrived together than the mailbox holds (a burst from the source)"
                                    : "the pipeline is behind (longer than max_frame_wait_ms)",
                               Ms(drop->since_last_take).count(), mailbox_.dropped()));
  }
}

void Daemon::on_source_state(SourceState state, std::string_view detail) {
  {
    std::lock_guard lock(state_mutex_);
    // Every start of streaming (first connect, reconnect, replay loop) is a new take for the filler.
    if (state == SourceState::Streaming) ++generation_;
    state_ = state;
    state_detail_ = std::string(detail);
  }
  spdlog::info("source: {} ({})", to_string(state), detail);
  broadcast_status();
}

void Daemon::on_bad_input(std::string_view what, std::string_view detail) {
  metrics_.count_bad_input(what);
  bad_input_log_.warn(what, detail);
}

void Daemon::on_rejected_points(uint32_t frame_number, int count) {
  metrics_.count_bad_input("rejected_point");
  bad_input_log_.warn("rejected_point", "frame " + std::to_string(frame_number) + ": " + std::to_string(count) +
                                            " points ignored (not finite, or beyond " +
                                            std::to_string(MarkerFrame::kMaxUnlabelled) + " unlabelled)");
}

void Daemon::on_match(int, bool present, std::string_view detail) {
  if (present) {
    // Back in the stream: a new take for its filler.
    std::lock_guard lock(state_mutex_);
    ++generation_;
  }
  if (present) spdlog::info("subject {}: {}", config_.subject, detail);
  else spdlog::warn("subject {}: absent, waiting for it: {}", config_.subject, detail);
}

void Daemon::on_unknown_subjects(std::span<const std::string> names, size_t not_listed) {
  for (const std::string& name : names) bad_input_log_.warn("unknown_subject", "source subject " + quoted_text(name) + " is none of ours: ignored");
  if (not_listed > 0)
    bad_input_log_.warn("unknown_subjects", std::to_string(not_listed) + " more source subjects that are none of ours (no longer listed)");
}

void Daemon::on_unknown_labels(int, std::span<const std::string> names, size_t not_listed) {
  for (const std::string& name : names) {
    metrics_.count_bad_input("unknown_label");
    // Rate-limited and made printable: the names come from the source, which may send thousands.
    bad_input_log_.warn("unknown_label", "source label " + quoted_text(name) + " is not a marker of the subject: used as an unlabelled point");
  }
  if (not_listed > 0)
    bad_input_log_.warn("unknown_labels", std::to_string(not_listed) + " more labels that are not markers of the subject (no longer listed)");
}

void Daemon::broadcast_status() {
  subscriber::Status status;
  {
    std::lock_guard lock(state_mutex_);
    status.state = code_of(state_);
    status.source_rate_hz = static_cast<float>(source_rate_hz_);
    status.detail = state_detail_;
    status.subject_present = state_ == SourceState::Streaming;
  }
  status.frames_received = metrics_.frames_received.load();
  status.frames_published = metrics_.frames_published.load();
  hub_->broadcast_status(status);
}

void Daemon::schedule_status() {
  status_timer_.expires_after(std::chrono::milliseconds(config_.status_interval_ms));
  status_timer_.async_wait([this](const boost::system::error_code& ec) {
    if (ec || stopping_.load()) return;
    broadcast_status();
    if (config_.subscriber_write_stall_ms > 0) hub_->drop_stalled_writers(std::chrono::milliseconds(config_.subscriber_write_stall_ms));
    pipeline_->size_pool_for(hub_->active_count());
    schedule_status();
  });
}

std::string Daemon::health_json() const {
  nlohmann::json source;
  {
    std::lock_guard lock(state_mutex_);
    source = {{"state", to_string(state_)}, {"detail", state_detail_}, {"rate_hz", source_rate_hz_}};
  }
  nlohmann::json allowed = nlohmann::json::array();  // as understood: "10.1.2.3" is shown as 10.1.2.3/32
  for (const SubscriberNetwork& network : admission_->options().allow) allowed.push_back(network.to_string());
  const nlohmann::json health = {
      {"status", "ok"},
      {"source", source},
      {"frames",
       {{"received", metrics_.frames_received.load()},
        {"processed", metrics_.frames_processed.load()},
        {"published", metrics_.frames_published.load()},
        {"dropped", metrics_.frames_dropped.load()},
        {"dropped_mailbox_full", metrics_.frames_dropped_mailbox_full.load()}}},
      // Encoded frame buffers created so far: grows only while the pool meets a new high-water
      // mark of frames in use (bounded by the subscribers' queues), so RSS steps with it.
      {"frame_buffers_allocated", metrics_.frame_buffers_allocated.load()},
      {"frame_buffers_allocated_by_pipeline", metrics_.frame_buffers_allocated_by_pipeline.load()},
      // Frames in the pool and held by subscribers now: back to what the subscribers need within
      // a second of stalled ones leaving.
      {"frame_pool", {{"frames", pipeline_->pool_frames()}, {"in_use", pipeline_->pool_frames_in_use()}}},
      {"subscribers", hub_->subscriber_count()},
      {"subscriber_limits",
       {{"max_subscribers", config_.max_subscribers},
        {"max_subscribers_per_address", config_.max_subscribers_per_address},
        {"write_stall_ms", config_.subscriber_write_stall_ms},
        {"allow_subscribers", allowed},
        {"token_required", admission_->token_required()},
        {"admitted", admission_->admitted()},
        {"refused_not_allowed", metrics_.subscribers_refused_not_allowed.load()},
        {"refused_limit", metrics_.subscribers_refused_limit.load()},
        {"refused_token", metrics_.subscribers_refused_token.load()},
        {"dropped_write_stall", metrics_.subscribers_dropped_write_stall.load()}}},
      {"deform", {{"threads", config_.deform_threads}, {"cpus", deform_cpus_}, {"spin_lead_us", config_.deform_spin_lead_us}}},
      {"publish_threads", publish_.count()},
      {"subscriber_tcp_congestion", config_.subscriber_tcp_congestion},  // empty: the system's
      {"subject", {{"markers", subject_.model.marker_count()}, {"vertices", pipeline_->vertex_count()}}},
      {"source_limits",
       {{"max_subjects", config_.source_max_subjects},
        {"max_markers_per_subject", config_.source_max_markers_per_subject},
        {"max_name_bytes", config_.source_max_name_bytes}}},
      {"latency_ms", latency_summaries(metrics_)}};
  return health.dump();
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
