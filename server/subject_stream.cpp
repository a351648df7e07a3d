#include "server/subject_stream.h"

#include <spdlog/fmt/ranges.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "core/deform/body_plausibility.h"
#include "protocol/files/file_error.h"
#include "protocol/subscriber/packed_message.h"
#include "protocol/subscriber/subscriber_model.h"

namespace skinstream::server {
namespace {

subscriber::MeshInfo mesh_info_of(const SubjectFile& subject) {
  subscriber::MeshInfo info;
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

// Stalled goes out as Disconnected (the protocol's subscribers know no other state), with its
// detail saying "stalled".
subscriber::SourceStateCode code_of(SourceState s) {
  switch (s) {
    case SourceState::Connecting: return subscriber::SourceStateCode::Connecting;
    case SourceState::Streaming: return subscriber::SourceStateCode::Streaming;
    case SourceState::Finished: return subscriber::SourceStateCode::Finished;
    case SourceState::Disconnected:
    case SourceState::Stalled: break;
  }
  return subscriber::SourceStateCode::Disconnected;
}

// The /metrics histograms condensed for scripts, over the stream's life: per stage its count,
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
  add("source_to_publish", metrics.source_to_publish);
  add("subscriber_queue_wait", metrics.subscriber_queue_wait);
  add("subscriber_write", metrics.subscriber_write);
  return out;
}

}  // namespace

// A subject file and what is made from it; replaced whole by a swap.
struct SubjectStream::Replacement {
  Replacement(std::string path, SubjectFile s, std::chrono::nanoseconds max_frame_wait)
      : file(std::move(path)), subject(std::move(s)), mailbox(subject.model.marker_count(), max_frame_wait) {}
  std::string file;
  SubjectFile subject;
  FrameMailbox mailbox;
  std::unique_ptr<Pipeline> pipeline;
  subscriber::MeshInfo mesh_info;
  ControlMessage model_message;  // null without a mesh
  SubscriberHub::PackedFirstContact packed;
  uint32_t epoch = 0;
  std::chrono::steady_clock::time_point retired;
};

namespace {

// The subject file read and checked as the daemon serves it: a body it would refuse (folded,
// crumpled, not a body) is refused here too.
SubjectFile read_served_subject(const std::string& file, const std::string& name) {
  SubjectFile subject = read_subject_file(file);
  if (subject.deformation)
    if (const std::string problem = implausible_body(subject.model, *subject.deformation); !problem.empty())
      throw FileError(file, "refused: " + problem);
  if (!subject.deformation)
    spdlog::warn(
        "subject {}: {}: no deformation model (built without --mesh): publishing markers only (MeshInfo with "
        "V = 0)",
        name, file);
  return subject;
}

}  // namespace

SubjectStream::SubjectStream(SubjectConfig config, const SubjectStreamOptions& options)
    : config_(std::move(config)),
      name_(config_.name.empty() ? std::filesystem::path(config_.file).stem().string() : config_.name),
      options_(options),
      deform_cpus_(options.pipeline.deform_cpus),
      deform_threads_(options.pipeline.deform_threads) {
  auto body = std::make_shared<Replacement>(config_.file, read_served_subject(config_.file, name_),
                                            options.max_frame_wait);
  subscriber::MeshInfo mesh_info = mesh_info_of(body->subject);
  mesh_info.subject = name_;
  const bool has_mesh = body->subject.deformation.has_value();
  hub_ = std::make_unique<SubscriberHub>(metrics_, options.hub, std::move(mesh_info), has_mesh);
  consumer_ = hub_.get();
  if (options.multicast) {
    if (!has_mesh)
      throw ConfigError("multicast sends the parameters of the mesh: subject " + name_ + " (" + config_.file + ") has none (built without --mesh)");
    multicast_ = std::make_unique<MulticastSender>(*hub_, *options.multicast);
    consumer_ = multicast_.get();
  }
  make_pipeline(*body, 0);
  Pipeline* pipeline = body->pipeline.get();
  hub_->set_encoding_preparer({.ready = [pipeline](StreamKey key) { return pipeline->encoding_ready(key); },
                               .request = [pipeline](StreamKey key) { pipeline->request_encoding(key); },
                               .activated = [pipeline](StreamKey key) { pipeline->encoding_activated(key); }});
  hub_->set_compressed_order(pipeline->compressed_order());
  pack_first_contact(*body);
  hub_->set_packed_first_contact(body->packed);
  if (body->model_message) {
    hub_->set_model_message(body->model_message);
    const EvaluationModel& evaluation = *pipeline->evaluation_model();
    spdlog::info(
        "subject {}: parameter encoding: Model message of {} bytes ({} parts, {} RBF centres, {} influences)",
        name_, body->model_message->size(), evaluation.part_count(), evaluation.member_count(),
        evaluation.influence_count());
    if (multicast_) {
      multicast_->set_model(
          std::span<const unsigned char>(*body->model_message).subspan(subscriber::kHeaderBytes));
      pipeline->prepare_encoding(MulticastSender::sent_key());
      const MulticastGroupAddress& frames = options.multicast->frames;
      spdlog::info(
          "subject {}: multicast: every frame's parameters to {}:{} from {} (TTL {}), stream {}, model id "
          "{:08x}",
          name_, frames.group, frames.port, frames.interface_address, frames.ttl,
          options.multicast->stream_id, multicast_->model_id());
    }
    if (multicast_ && options.multicast->offer_mbit > 0) {
      offer_ = std::make_unique<MulticastOffer>(*options.multicast, [hub = hub_.get()] {
        const SubscriberHub::PackedParameterJoin join = hub->packed_parameter_join();
        return MulticastOffer::Content{join.mesh_info, join.model, join.plain_model};
      });
      spdlog::info(
          "subject {}: multicast: the packed MeshInfo and Model offered round and round to {}:{} at {} "
          "Mbit/s",
          name_, options.multicast->frames.group, options.multicast->offer_address().port,
          options.multicast->offer_mbit);
    }
  }
  input_ = body.get();
  body_ = std::move(body);
}

void SubjectStream::make_pipeline(Replacement& body, uint32_t epoch) {
  PipelineOptions options = options_.pipeline;
  options.model_epoch = epoch;
  body.epoch = epoch;
  const SubjectFile& subject = body.subject;
  try {
    body.pipeline =
        std::make_unique<Pipeline>(subject.model, subject.deformation ? &*subject.deformation : nullptr,
                                   options, body.mailbox, *consumer_, metrics_);
  } catch (const std::invalid_argument& e) {
    throw FileError(body.file, std::string("deformation model unusable: ") + e.what());
  }
  Pipeline* pipeline = body.pipeline.get();
  pipeline->set_encoding_ready_callback([hub = hub_.get()](StreamKey key) { hub->encoding_prepared(key); });
  body.mesh_info = mesh_info_of(subject);
  if (const EvaluationModel* evaluation = pipeline->evaluation_model())
    body.model_message =
        std::make_shared<const std::vector<unsigned char>>(subscriber::encode_model(*evaluation));
}

void SubjectStream::pack_first_contact(Replacement& body) {
  const auto start = std::chrono::steady_clock::now();
  body.packed =
      hub_->pack_first_contact(body.mesh_info, body.pipeline->compressed_order(), body.model_message);
  // A Packed message's size, and the plain message's it holds (header included).
  size_t packed = 0, plain = 0;
  for (const ControlMessage& m :
       {body.packed.mesh_info[static_cast<size_t>(subscriber::Encoding::Parameters)], body.packed.model}) {
    if (!m) continue;
    packed += m->size();
    plain += subscriber::plain_message_bytes(*m);
  }
  spdlog::info(
      "subject {}: what a parameter subscriber is sent as it joins, packed in {:.2f} s: {} bytes (plain {})",
      name_, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), packed, plain);
}

std::shared_ptr<SubjectStream::Replacement> SubjectStream::prepare_replacement(const std::string& file) {
  auto body = std::make_shared<Replacement>(file, read_served_subject(file, name_), options_.max_frame_wait);
  if (body->subject.deformation.has_value() != has_mesh())
    throw FileError(file, has_mesh()
                              ? "refused: it has no deformation model (built without --mesh), and subject " +
                                    name_ + "'s subscribers receive a mesh"
                              : "refused: it has a deformation model, and subject " + name_ +
                                    " is served as markers only (restart the daemon to serve a mesh)");
  make_pipeline(*body, last_epoch_.fetch_add(1) + 1);
  pack_first_contact(*body);
  // The buffers of every encoding its subscribers receive, made here: its first frames would
  // otherwise make them on its thread.
  hub_->wanted_encodings().for_each([&](StreamKey key) { body->pipeline->prepare_encoding(key); });
  if (multicast_) body->pipeline->prepare_encoding(MulticastSender::sent_key());
  return body;
}

const SubjectModel& SubjectStream::model() const { return input_->subject.model; }

MarkerFrame& SubjectStream::writable() { return input_->mailbox.writable(); }

const SubjectModel& SubjectStream::model_of(const Replacement& replacement) {
  return replacement.subject.model;
}

void SubjectStream::switch_input(Replacement& replacement) { input_ = &replacement; }

void SubjectStream::complete_replacement(std::shared_ptr<Replacement> next) {
  const std::shared_ptr<Replacement> old = served();
  old->pipeline->stop();  // its last frame published; nothing publishes until the new one starts
  next->mailbox.add_counts_of(old->mailbox);
  Pipeline* pipeline = next->pipeline.get();
  if (multicast_ && next->model_message)
    multicast_->set_model(
        std::span<const unsigned char>(*next->model_message).subspan(subscriber::kHeaderBytes));
  hub_->replace_model({next->mesh_info,
                       next->model_message,
                       pipeline->compressed_order(),
                       {.ready = [pipeline](StreamKey key) { return pipeline->encoding_ready(key); },
                        .request = [pipeline](StreamKey key) { pipeline->request_encoding(key); },
                        .activated = [pipeline](StreamKey key) { pipeline->encoding_activated(key); }},
                       next->epoch,
                       next->packed});
  pipeline->set_filled_observer(take_tap_);
  pipeline->start();
  old->retired = std::chrono::steady_clock::now();
  std::lock_guard lock(mutex_);
  config_.file = next->file;
  retired_.push_back(old);
  body_ = std::move(next);
}

std::shared_ptr<SubjectStream::Replacement> SubjectStream::served() const {
  std::lock_guard lock(mutex_);
  return body_;
}

SubjectConfig SubjectStream::config() const {
  std::lock_guard lock(mutex_);
  return config_;
}

uint32_t SubjectStream::vertex_count() const { return served()->pipeline->vertex_count(); }

void SubjectStream::render_multicast_metrics(std::string& out) const {
  if (multicast_) multicast_->render_prometheus(out);
  if (offer_) offer_->render_prometheus(out);
}

SubjectStream::~SubjectStream() { stop(); }

void SubjectStream::start() {
  served()->pipeline->start();
  if (offer_) offer_->start();
}

void SubjectStream::stop() {
  if (offer_) offer_->stop();
  served()->pipeline->stop();
}

void SubjectStream::set_take_tap(TakeTap* tap) {
  take_tap_ = tap;
  served()->pipeline->set_filled_observer(tap);
}

void SubjectStream::post() {
  metrics_.frames_received.fetch_add(1, std::memory_order_relaxed);
  FrameMailbox& mailbox = input_->mailbox;
  const MarkerFrame& frame = mailbox.writable();
  if (frame.rejected_points > 0) {
    metrics_.count_bad_input("rejected_point");
    bad_input_log_.warn("rejected_point", "subject " + name_ + ", frame " + std::to_string(frame.frame_number) + ": " +
                                              std::to_string(frame.rejected_points) + " points ignored (not finite, or beyond " +
                                              std::to_string(MarkerFrame::kMaxUnlabelled) + " unlabelled)");
  }
  if (frame.implausible_points > 0) {
    metrics_.count_bad_input("implausible_point");
    bad_input_log_.warn("implausible_point", "subject " + name_ + ", frame " + std::to_string(frame.frame_number) + ": " +
                                                 std::to_string(frame.implausible_points) +
                                                 " points taken as missing (outside the capture volume, source_max_coordinate_m)");
  }
  if (take_tap_) take_tap_->record_received(frame);
  if (frame.source_rate_hz > 0 && frame.source_rate_hz != source_rate_hz_) {
    source_rate_hz_ = frame.source_rate_hz;
    hub_->set_source_rate(static_cast<float>(frame.source_rate_hz));
  }
  if (const std::optional<FrameMailbox::Drop> drop = mailbox.post(generation_)) {
    // Says which side fell behind: the pipeline (it took nothing for a while), or the source,
    // whose frames came in a burst longer than the mailbox holds.
    using Ms = std::chrono::duration<double, std::milli>;
    const bool full = drop->reason == FrameMailbox::DropReason::kMailboxFull;
    drop_log_.warn(
        "frame_gave_way",
        fmt::format("subject {}: frame {} gave way to newer ones after waiting {:.1f} ms: {}; the pipeline "
                    "last took a "
                    "frame {:.1f} ms before ({} dropped in all)",
                    name_, drop->frame_number, Ms(drop->waited).count(),
                    full ? "more frames arrived together than the mailbox holds (a burst from the source)"
                         : "the pipeline is behind (longer than max_frame_wait_ms)",
                    Ms(drop->since_last_take).count(), mailbox.dropped()));
  }
}

void SubjectStream::set_presence(bool present, std::string_view detail) {
  if (present) new_take();  // (back) in the stream: the filler starts afresh
  {
    std::lock_guard lock(mutex_);
    present_ = present;
    presence_detail_ = std::string(detail);
  }
  if (present) spdlog::info("subject {}: {}", name_, detail);
  else spdlog::warn("subject {}: absent, waiting for it: {}", name_, detail);
}

bool SubjectStream::present() const {
  std::lock_guard lock(mutex_);
  return present_;
}

void SubjectStream::broadcast_status(SourceState state, std::string_view source_detail) {
  subscriber::Status status;
  status.state = code_of(state);
  status.source_rate_hz = static_cast<float>(source_rate_hz_);
  status.frames_received = metrics_.frames_received.load();
  status.frames_published = metrics_.frames_published.load();
  {
    std::lock_guard lock(mutex_);
    const auto now = RateSampler::Clock::now();
    if (published_rate_.seconds_since_sample(now) >= 0.5)
      published_fps_ = published_rate_.sample(status.frames_published, now).per_second();
    status.subject_present = present_;
    status.detail = present_ || state != SourceState::Streaming
                        ? std::string(source_detail)
                        : "subject " + name_ + " absent, waiting for it: " + presence_detail_;
  }
  hub_->broadcast_status(status);
}

void SubjectStream::tend_subscribers(std::chrono::milliseconds write_stall) {
  if (write_stall.count() > 0) hub_->drop_stalled_writers(write_stall);
  served()->pipeline->trim_pool();
  // A replaced model's frames may still be queued for a subscriber, its pool's buffers in use;
  // its encoding preparer may still be called by a subscriber's thread for a moment.
  std::lock_guard lock(mutex_);
  const auto now = std::chrono::steady_clock::now();
  std::erase_if(retired_, [&](const std::shared_ptr<Replacement>& r) {
    return r->pipeline->pool_frames_in_use() == 0 && now - r->retired > std::chrono::seconds(10);
  });
}

bool SubjectStream::holds_nothing() const {
  if (hub_->subscriber_count() > 0) return false;
  std::lock_guard lock(mutex_);
  if (body_->pipeline->pool_frames_in_use() > 0) return false;
  return std::all_of(retired_.begin(), retired_.end(),
                     [](const auto& r) { return r->pipeline->pool_frames_in_use() == 0; });
}

std::string SubjectStream::status_line(StatusLine::Clock::time_point now) {
  uint64_t subscriber_drops = 0;
  for (const SubscriberMetrics& m : hub_->subscriber_metrics()) subscriber_drops += m.dropped;
  return status_line_.next(name_, metrics_, hub_->subscriber_count(), subscriber_drops, now);
}

nlohmann::json SubjectStream::health() const {
  nlohmann::json out;
  {
    std::lock_guard lock(mutex_);
    // present: in the source's latest frames (the daemon waits for an absent one).
    out = {{"name", name_}, {"file", config_.file}, {"present", present_}, {"detail", presence_detail_}, {"fps", published_fps_}};
  }
  const std::shared_ptr<Replacement> body = served();
  const Pipeline& pipeline = *body->pipeline;
  out["markers"] = body->subject.model.marker_count();
  out["vertices"] = pipeline.vertex_count();
  out["model_epoch"] = body->epoch;
  out["frames"] = {{"received", metrics_.frames_received.load()},
                   {"processed", metrics_.frames_processed.load()},
                   {"published", metrics_.frames_published.load()},
                   {"dropped", metrics_.frames_dropped.load()},
                   {"dropped_mailbox_full", metrics_.frames_dropped_mailbox_full.load()}};
  out["source_rate_changes"] = metrics_.source_rate_changes.load();
  // Encoded frame buffers created so far: grows only while the pool meets a new high-water
  // mark of frames in use (bounded by the subscribers' queues) or an encoding is asked for
  // again after its buffers were released, so RSS steps with it.
  out["frame_buffers_allocated"] = metrics_.frame_buffers_allocated.load();
  out["frame_buffers_allocated_by_pipeline"] = metrics_.frame_buffers_allocated_by_pipeline.load();
  out["frame_buffers_released"] = metrics_.frame_buffers_released.load();
  out["subscribers"] = hub_->subscriber_count();
  out["deform"] = {{"threads", deform_threads_}, {"cpus", deform_cpus_}};
  out["latency_ms"] = latency_summaries(metrics_);
  // Frames in the pool and held by subscribers now, and the most held at once since the last
  // Status tick: within two ticks of stalled subscribers leaving, the pool is back to that high
  // water mark plus the frames kept free.
  out["frame_pool"] = {{"frames", pipeline.pool_frames()},
                       {"in_use", pipeline.pool_frames_in_use()},
                       {"in_use_high_water", pipeline.pool_frames_in_use_high_water()},
                       {"kept_free", Pipeline::pool_frames_kept_free()},
                       {"unwanted_encoding_hold_off_s", Pipeline::unwanted_encoding_hold_off().count()}};
  if (multicast_) {
    out["multicast"] = multicast_->health();
    if (offer_) out["multicast"]["offer"] = offer_->health();
  }
  return out;
}

}  // namespace skinstream::server
