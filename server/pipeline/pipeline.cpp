#include "server/pipeline/pipeline.h"

#include <spdlog/spdlog.h>

#include <chrono>
#include <stdexcept>

#include "protocol/subscriber_stream.h"
#include "server/pipeline/deform_cpus.h"
#include "server/thread_name.h"

namespace skinstream::server {
namespace {

int64_t wall_clock_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
}

int64_t since_ns(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - start).count();
}

uint16_t clamp16(int v) { return static_cast<uint16_t>(std::clamp(v, 0, 65535)); }

}  // namespace

Pipeline::Pipeline(const SubjectModel& model, const DeformationModel* deformation, const PipelineOptions& options,
                   FrameMailbox& mailbox, FrameConsumer& consumer, Metrics& metrics)
    : model_(model),
      options_(options),
      mailbox_(mailbox),
      consumer_(consumer),
      metrics_(metrics),
      blender_(model, options.lookahead) {
  const int n = model.marker_count();
  filled_.resize(n);
  released_positions_.resize(n);
  filled_status_.resize(n);
  released_status_.resize(n);
  held_.resize(static_cast<size_t>(options.lookahead) + 1);
  marker_floats_.resize(3 * static_cast<size_t>(n));
  marker_status_bytes_.resize(n);
  GapFillerOptions filler_options = options.filler;
  filler_rate_hz_ = filler_options.rate_hz = options.default_rate_hz;
  filler_.emplace(model_, filler_options);
  if (deformation) {
    deformer_ = std::make_unique<MeshDeformer>(*deformation, model);
    positions_.resize(3 * static_cast<size_t>(deformer_->vertex_count()));
    normals_.resize(positions_.size());
    workers_ = std::make_unique<DeformWorkers>(
        *deformer_, DeformWorkerOptions{options.deform_threads, options.deform_spin_lead, options.deform_cpus, options.deform_thread_name});
    if (workers_->unpinned_workers() > 0)
      spdlog::warn("pipeline: {} deform worker(s) could not be pinned to their CPU; they run where the OS puts them",
                   workers_->unpinned_workers());
  }
}

Pipeline::~Pipeline() { stop(); }

void Pipeline::start() {
  if (running_.exchange(true)) return;
  thread_ = std::thread([this] {
    name_this_thread(options_.thread_name);
    run();
  });
}

void Pipeline::stop() {
  running_.store(false);
  mailbox_.close();
  if (thread_.joinable()) thread_.join();
}

void Pipeline::run() {
  if (!options_.deform_cpus.empty() && deformer_ && !pin_this_thread(options_.deform_cpus.front()))
    spdlog::warn("pipeline: could not pin the pipeline thread to CPU {}; it runs where the OS puts it", options_.deform_cpus.front());
  while (running_.load()) {
    uint64_t generation = 0;
    const MarkerFrame* frame = mailbox_.take(std::chrono::milliseconds(100), generation);
    if (!frame) continue;
    if (frame->receive_time_ns > 0) metrics_.receive_to_take.observe_ns(wall_clock_ns() - frame->receive_time_ns);
    try {
      process(*frame, generation);
    } catch (const std::exception& e) {
      // Nothing in the per-frame path throws by design; if it does, lose the frame, not the daemon.
      metrics_.count_bad_input("pipeline_error");
      spdlog::error("pipeline: frame {} dropped: {}", frame->frame_number, e.what());
    }
  }
}

void Pipeline::process(const MarkerFrame& frame, uint64_t generation) {
  if (!has_generation_ || generation != generation_) {
    // A new stream (reconnect, replay restarted): the past no longer predicts this frame.
    filler_->reset();
    blender_.reset();
    generation_ = generation;
    has_generation_ = true;
  }
  if (frame.source_rate_hz > 0 && std::abs(frame.source_rate_hz - filler_rate_hz_) > 1e-6) {
    // Rare (the rate becomes known): rebuilding allocates, which is fine here.
    GapFillerOptions filler_options = options_.filler;
    filler_rate_hz_ = filler_options.rate_hz = frame.source_rate_hz;
    filler_.emplace(model_, filler_options);
    blender_.reset();
    spdlog::info("pipeline: source rate {} Hz", frame.source_rate_hz);
  }

  // The deform worker's wake-up (tens to hundreds of microseconds on a busy host) overlaps the fill.
  if (workers_) workers_->get_ready();
  const auto fill_start = std::chrono::steady_clock::now();
  const size_t free_count = static_cast<size_t>(std::clamp(frame.unlabelled_count, 0, MarkerFrame::kMaxUnlabelled));
  const FrameInput input{frame.labelled, std::span(frame.unlabelled).first(free_count),
                         std::span(frame.unlabelled_ids).first(free_count)};
  const FillStats stats = filler_->run(input, {filled_, filled_status_});
  metrics_.fill.observe_ns(since_ns(fill_start));
  if (!stats.ok) {
    metrics_.count_bad_input("wrong_marker_count");
    return;
  }
  metrics_.frames_processed.fetch_add(1, std::memory_order_relaxed);
  metrics_.markers_filled.fetch_add(static_cast<uint64_t>(stats.filled + stats.held), std::memory_order_relaxed);
  metrics_.markers_relabelled.fetch_add(static_cast<uint64_t>(stats.relabelled), std::memory_order_relaxed);
  metrics_.markers_held.fetch_add(static_cast<uint64_t>(stats.held), std::memory_order_relaxed);

  const long sequence = sequence_++;
  held_[static_cast<size_t>(sequence) % held_.size()] = {frame.frame_number, frame.source_time_ns, frame.receive_time_ns,
                                                        clamp16(stats.filled + stats.held), clamp16(stats.relabelled), frame.timecode};
  long released = 0;
  if (blender_.push(filled_, filled_status_, sequence, {released_positions_, released_status_}, released))
    publish(held_[static_cast<size_t>(released) % held_.size()], released_positions_, released_status_);
}

size_t Pipeline::message_bytes(uint32_t slot) const {
  const uint32_t flags = slot_frame_flags(slot);
  return subscriber::frame_message_bytes(flags, (flags & subscriber::kFrameNoPositions) ? 0 : vertex_count(),
                                         (flags & subscriber::kFrameMarkers) ? static_cast<uint32_t>(model_.marker_count()) : 0,
                                         slot_version(slot));
}

void Pipeline::prepare_encoding(uint32_t slot) {
  const size_t made = pool_.prepare(slot, message_bytes(slot));
  metrics_.frame_buffers_allocated.fetch_add(made, std::memory_order_relaxed);
}

void Pipeline::publish(const Released& meta, std::span<const Vec3> positions, std::span<const MarkerStatus> status) {
  const uint32_t wanted = consumer_.wanted_encodings();
  bool want_normals = false;
  for (uint32_t slot = 0; slot < EncodedFrame::kEncodings; ++slot)
    if (((wanted >> slot) & 1u) && (slot_frame_flags(slot) & subscriber::kFrameNormals)) want_normals = true;

  if (deformer_) {
    const auto start = std::chrono::steady_clock::now();
    if (workers_->run(positions, positions_, want_normals ? std::span<float>(normals_) : std::span<float>())) {
      metrics_.deform.observe_ns(since_ns(start) - workers_->last_normals_ns());
      if (want_normals) metrics_.normals.observe_ns(workers_->last_normals_ns());
    } else {
      metrics_.count_bad_input("deform_failed");
    }
  }

  const auto encode_start = std::chrono::steady_clock::now();
  for (size_t m = 0; m < status.size(); ++m) {
    for (int a = 0; a < 3; ++a) marker_floats_[3 * m + a] = static_cast<float>(positions[m][a]);
    marker_status_bytes_[m] = static_cast<uint8_t>(status[m]);
  }
  FrameRef ref = pool_.acquire();
  EncodedFrame& out = *ref.mutable_frame();
  subscriber::FrameInfo info;
  info.frame_number = meta.frame_number;
  info.source_time_ns = meta.source_time_ns;
  info.receive_time_ns = meta.receive_time_ns;
  info.publish_time_ns = 0;  // stamped below, once every encoding is written
  info.vertex_count = vertex_count();
  info.marker_count = static_cast<uint32_t>(status.size());
  info.markers_filled = meta.filled;
  info.markers_relabelled = meta.relabelled;
  info.pipeline_dropped = static_cast<uint32_t>(mailbox_.dropped());
  const SourceTimecode& tc = meta.timecode;
  info.timecode = {tc.hours, tc.minutes, tc.seconds, tc.frames, tc.subframe, tc.subframes_per_frame, tc.rate_hz,
                   (tc.drop_frame ? subscriber::kTimecodeDropFrame : 0u) | (tc.field ? subscriber::kTimecodeField : 0u)};
  out.frame_number = meta.frame_number;
  for (uint32_t f = 0; f < EncodedFrame::kEncodings; ++f) {
    if (!((wanted >> f) & 1u)) continue;
    const uint16_t version = slot_version(f);
    info.flags = slot_frame_flags(f) | (version >= 2 && tc.valid ? subscriber::kFrameTimecode : 0u);
    const size_t bytes = message_bytes(f);
    if (pool_.size_message(out, f, bytes)) {  // first use of this encoding in this pooled frame, nothing prepared
      metrics_.frame_buffers_allocated.fetch_add(1, std::memory_order_relaxed);
      metrics_.frame_buffers_allocated_by_pipeline.fetch_add(1, std::memory_order_relaxed);
    }
    subscriber::encode_frame(info, positions_, normals_, marker_floats_, marker_status_bytes_, out.messages[f], version);
    out.encoded_mask |= 1u << f;
  }
  metrics_.encode.observe_ns(since_ns(encode_start));
  // The publish time is taken last, so that publish - receive (in every frame's header) is the
  // daemon's whole processing, encoding included; delivery starts here.
  out.publish_time_ns = wall_clock_ns();
  out.published = std::chrono::steady_clock::now();
  for (uint32_t f = 0; f < EncodedFrame::kEncodings; ++f)
    if ((out.encoded_mask >> f) & 1u) subscriber::patch_publish_time(out.messages[f], out.publish_time_ns);
  metrics_.frames_dropped.store(mailbox_.dropped(), std::memory_order_relaxed);
  metrics_.frames_dropped_mailbox_full.store(mailbox_.dropped_mailbox_full(), std::memory_order_relaxed);
  // Counted before the hand-over, so that no reader of the counters (/health, the bench) can
  // find a subscriber holding a frame the count does not include yet: a publish thread may
  // write it out before this thread runs its next line.
  published_.fetch_add(1, std::memory_order_relaxed);
  metrics_.frames_published.fetch_add(1, std::memory_order_relaxed);
  consumer_.publish(ref);
  if (meta.receive_time_ns > 0) metrics_.receive_to_publish.observe_ns(wall_clock_ns() - meta.receive_time_ns);
}

}  // namespace skinstream::server
