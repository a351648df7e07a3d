#include "server/pipeline/pipeline.h"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <stdexcept>

#include "protocol/subscriber/finite_values.h"
#include "protocol/subscriber/frame_parameters.h"
#include "protocol/subscriber/subscriber_stream.h"
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

subscriber::FrameTimecode frame_timecode(const SourceTimecode& t) {
  return {t.hours, t.minutes, t.seconds, t.frames, t.subframe, t.subframes_per_frame, t.rate_hz,
          (t.drop_frame ? subscriber::kTimecodeDropFrame : 0u) | (t.field ? subscriber::kTimecodeField : 0u)};
}

// What one frame's subscribers need computed, from the stream keys they hold.
struct FrameNeeds {
  bool vertices = false;             // some encoding sends positions (float, quantised, compressed)
  bool normals = false;              // ... with normals
  bool parameters = false;           // some subscriber takes the parameters
  bool compressed = false;
  bool compressed_normals = false;
};

bool all_finite(const FrameParameters& parameters) {
  for (const PartParameters& part : parameters.parts)
    if (!skinstream::all_finite(part.quadratic) || !skinstream::all_finite(part.rotation) || !skinstream::all_finite(part.translation))
      return false;
  return skinstream::all_finite(parameters.weights);
}

FrameNeeds needs_of(const StreamKeySet& wanted) {
  FrameNeeds needs;
  wanted.for_each([&](StreamKey key) {
    const uint32_t flags = stream_flags(key);
    if (flags & subscriber::kFrameNoPositions) return;
    if (flags & subscriber::kFrameParameters) {
      needs.parameters = true;
      return;
    }
    needs.vertices = true;
    needs.normals |= (flags & subscriber::kFrameNormals) != 0;
    if (flags & subscriber::kFrameCompressed) {
      needs.compressed = true;
      needs.compressed_normals |= (flags & subscriber::kFrameNormals) != 0;
    }
  });
  return needs;
}

// What of a frame about to be encoded is not all finite ("markers", "vertices", ...), or null.
const char* non_finite_output(const FrameNeeds& needs, std::span<const float> markers, const MeshDeformer* deformer,
                              std::span<const float> positions, std::span<const float> normals) {
  if (!skinstream::all_finite(markers)) return "markers";
  if (!deformer) return nullptr;
  if (needs.vertices && !skinstream::all_finite(positions)) return "vertices";
  if (needs.vertices && needs.normals && !skinstream::all_finite(normals)) return "normals";
  if (needs.parameters && !all_finite(deformer->parameters())) return "parameters";
  return nullptr;
}

}  // namespace

Pipeline::Pipeline(const SubjectModel& model, const DeformationModel* deformation, const PipelineOptions& options,
                   FrameMailbox& mailbox, FrameConsumer& consumer, Metrics& metrics)
    : model_(model),
      options_(options),
      mailbox_(mailbox),
      consumer_(consumer),
      metrics_(metrics),
      pool_keeper_("frame-pool", [this] { keep_pool(); }),
      blender_(model, options.lookahead) {
  const int n = model.marker_count();
  filled_.resize(n);
  released_positions_.resize(n);
  filled_status_.resize(n);
  filled_revoked_.resize(n);
  released_status_.resize(n);
  held_.resize(static_cast<size_t>(options.lookahead) + 1);
  marker_floats_.resize(3 * static_cast<size_t>(n));
  marker_status_bytes_.resize(n);
  filler_rate_hz_ = options.default_rate_hz;
  filler_.emplace(model_, filler_options(filler_rate_hz_));
  if (deformation) {
    deformer_ = std::make_unique<MeshDeformer>(*deformation, model);
    positions_.resize(3 * static_cast<size_t>(deformer_->vertex_count()));
    normals_.resize(positions_.size());
    workers_ = std::make_unique<DeformWorkers>(
        *deformer_, DeformWorkerOptions{options.deform_threads, options.deform_spin_lead, options.deform_cpus, options.deform_thread_name});
    const EvaluationModel& evaluation = deformer_->evaluation_model();
    parameter_block_.resize(subscriber::parameter_block_bytes(evaluation.part_count(), evaluation.member_count()));
    compressed_order_ = subscriber::compressed_vertex_order(evaluation.reference_vertices);
    compressed_ = std::make_unique<subscriber::CompressedVertexEncoder>(deformer_->vertex_count(), compressed_order_,
                                                                        options.compressed_key_interval);
    compressed_blocks_.resize(compressed_->max_bytes(true));
    if (workers_->unpinned_workers() > 0)
      spdlog::warn("pipeline: {} deform worker(s) could not be pinned to their CPU; they run where the OS puts them",
                   workers_->unpinned_workers());
  }
}

Pipeline::~Pipeline() { stop(); }

// As core/capture_filler.cpp runs it: new relabels confirmed within the lookahead.
GapFillerOptions Pipeline::filler_options(double rate_hz) const {
  GapFillerOptions o = options_.filler;
  o.rate_hz = rate_hz;
  o.confirm_frames = options_.lookahead;
  return o;
}

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
  if (rate_changed(frame.source_rate_hz)) {
    // Rare (the rate becomes known, the operator changes it): rebuilding allocates, which is fine here.
    filler_rate_hz_ = frame.source_rate_hz;
    last_rate_change_ = std::chrono::steady_clock::now();
    filler_.emplace(model_, filler_options(filler_rate_hz_));
    blender_.reset();
    metrics_.source_rate_changes.fetch_add(1, std::memory_order_relaxed);
    spdlog::info("pipeline: source rate {} Hz", frame.source_rate_hz);
  }

  // The deform worker's wake-up (tens to hundreds of microseconds on a busy host) overlaps the fill.
  if (workers_) workers_->get_ready();
  const auto fill_start = std::chrono::steady_clock::now();
  const size_t free_count = static_cast<size_t>(std::clamp(frame.unlabelled_count, 0, MarkerFrame::kMaxUnlabelled));
  const FrameInput input{frame.labelled, std::span(frame.unlabelled).first(free_count),
                         std::span(frame.unlabelled_ids).first(free_count)};
  const FillStats stats = filler_->run(input, {filled_, filled_status_, {}, filled_revoked_});
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
  held_[static_cast<size_t>(sequence) % held_.size()] = {frame.frame_number,
                                                         frame.source_time_ns,
                                                         frame.receive_time_ns,
                                                         frame.capture_latency_ns,
                                                         clamp16(stats.filled + stats.held),
                                                         clamp16(stats.relabelled),
                                                         frame_timecode(frame.timecode),
                                                         frame.timecode.valid};
  long released = 0;
  if (blender_.push(filled_, filled_status_, sequence, {released_positions_, released_status_}, released, filled_revoked_))
    publish(held_[static_cast<size_t>(released) % held_.size()], released_positions_, released_status_);
}

bool Pipeline::rate_changed(double source_rate_hz) const {
  if (!(source_rate_hz > 0.0) || std::abs(source_rate_hz - filler_rate_hz_) <= kRateTolerance * filler_rate_hz_) return false;
  return last_rate_change_ == std::chrono::steady_clock::time_point{} ||
         std::chrono::steady_clock::now() - last_rate_change_ >= kMinRateChangeInterval;
}

size_t Pipeline::message_bytes(StreamKey key) const {
  const uint32_t flags = stream_flags(key);
  const uint32_t markers = (flags & subscriber::kFrameMarkers) ? static_cast<uint32_t>(model_.marker_count()) : 0;
  if ((flags & subscriber::kFrameParameters) && deformer_)
    return subscriber::frame_message_bytes_with_block(parameter_block_.size(), flags, markers);
  if ((flags & subscriber::kFrameCompressed) && compressed_)
    return subscriber::frame_message_bytes_with_block(compressed_->max_bytes(flags & subscriber::kFrameNormals), flags, markers);
  return subscriber::frame_message_bytes(flags, (flags & subscriber::kFrameNoPositions) ? 0 : vertex_count(), markers,
                                         stream_version(key));
}

void Pipeline::prepare_encoding(StreamKey key) {
  const size_t made = pool_.prepare(key, message_bytes(key));
  metrics_.frame_buffers_allocated.fetch_add(made, std::memory_order_relaxed);
  encoding_activated(key);
}

bool Pipeline::encoding_ready(StreamKey key) const { return pool_.prepared(key, message_bytes(key)); }

void Pipeline::request_encoding(StreamKey key) {
  {
    std::lock_guard lock(keeper_mutex_);
    requested_encodings_.add(key);
  }
  pool_keeper_.wake();
}

void Pipeline::encoding_activated(StreamKey key) {
  if ((stream_flags(key) & subscriber::kFrameCompressed) && compressed_) compressed_->request_key();
}

void Pipeline::trim_pool() {
  {
    std::lock_guard lock(keeper_mutex_);
    trim_asked_ = true;
  }
  pool_keeper_.wake();
}

// Everything that makes or frees pooled memory while frames flow happens here, on a thread that
// serves no one: the frames kept free ahead of the pipeline, the encodings subscribers wait for,
// then the trim.
void Pipeline::keep_pool() {
  for (;;) {
    // The frames ahead of the pipeline first: without them it would make its own.
    metrics_.frame_buffers_allocated.fetch_add(pool_.keep_free(kFreeFrames), std::memory_order_relaxed);
    StreamKey key = 0;
    {
      std::lock_guard lock(keeper_mutex_);
      if (requested_encodings_.empty()) break;
      requested_encodings_.for_each([&](StreamKey k) { key = k; });
      requested_encodings_.remove(key);
    }
    metrics_.frame_buffers_allocated.fetch_add(pool_.prepare(key, message_bytes(key)), std::memory_order_relaxed);
    if (encoding_ready_callback_) encoding_ready_callback_(key);
  }
  bool trim = false;
  {
    std::lock_guard lock(keeper_mutex_);
    std::swap(trim, trim_asked_);
  }
  if (trim) {
    const size_t released = pool_.release_unwanted(consumer_.wanted_encodings(), std::chrono::steady_clock::now(), kUnwantedHoldOff);
    metrics_.frame_buffers_released.fetch_add(released, std::memory_order_relaxed);
    pool_.trim(kFreeFrames);
  }
  metrics_.frame_buffers_allocated.fetch_add(pool_.keep_free(kFreeFrames), std::memory_order_relaxed);
}

void Pipeline::publish(const Released& meta, std::span<const Vec3> positions, std::span<const MarkerStatus> status) {
  const StreamKeySet wanted = consumer_.wanted_encodings();
  const FrameNeeds needs = needs_of(wanted);

  // The mesh only when someone takes vertices; the part fits alone when only parameters are
  // wanted; nothing for markers alone.
  // A frame the deformer refuses keeps the last fit and mesh (as the float encoding always did).
  if (deformer_ && (needs.vertices || needs.parameters)) {
    const auto start = std::chrono::steady_clock::now();
    const std::span<float> vertices = needs.vertices ? std::span<float>(positions_) : std::span<float>();
    const std::span<float> normals = needs.vertices && needs.normals ? std::span<float>(normals_) : std::span<float>();
    if (workers_->run(positions, vertices, normals)) {
      metrics_.deform.observe_ns(since_ns(start) - workers_->last_normals_ns());
      if (!normals.empty()) metrics_.normals.observe_ns(workers_->last_normals_ns());
    } else {
      metrics_.count_bad_input("deform_failed");
    }
  }

  const auto encode_start = std::chrono::steady_clock::now();
  for (size_t m = 0; m < status.size(); ++m) {
    for (int a = 0; a < 3; ++a) marker_floats_[3 * m + a] = static_cast<float>(positions[m][a]);
    marker_status_bytes_[m] = static_cast<uint8_t>(status[m]);
  }
  // Nothing that is not finite is encoded: a frame whose markers, vertices or parameters are not
  // all finite (a value the router should have refused, a deformation that overflowed) is
  // counted and not sent; subscribers keep the last good one.
  if (const char* what = non_finite_output(needs, marker_floats_, deformer_.get(), positions_, normals_)) {
    metrics_.count_bad_input("non_finite_frame");
    non_finite_log_.warn("non_finite_frame", "pipeline: frame " + std::to_string(meta.frame_number) + " not sent: its " + what +
                                                 " are not all finite");
    return;
  }
  if (filled_observer_)
    filled_observer_->on_filled(
        {meta.frame_number, meta.source_time_ns, meta.receive_time_ns, positions, status});
  subscriber::FrameInfo info;
  info.frame_number = meta.frame_number;
  info.source_time_ns = meta.source_time_ns;
  info.receive_time_ns = meta.receive_time_ns;
  info.publish_time_ns = 0;  // stamped when handed over, once every encoding of the ref is written
  info.marker_count = static_cast<uint32_t>(status.size());
  info.markers_filled = meta.filled;
  info.markers_relabelled = meta.relabelled;
  info.pipeline_dropped = static_cast<uint32_t>(mailbox_.dropped());
  info.timecode = meta.timecode;
  // Two hand-overs: every encoding but the compressed one first, then the compressed one, whose
  // vertex codec takes about a millisecond a frame (docs/measurements-log.md): its subscribers
  // wait for it, the others do not. Each subscriber takes the ref that holds its key.
  if (deformer_ && needs.parameters) subscriber::encode_parameter_block(deformer_->parameters(), parameter_block_);
  StreamKeySet first, compressed_keys;
  wanted.for_each([&](StreamKey key) { ((stream_flags(key) & subscriber::kFrameCompressed) ? compressed_keys : first).add(key); });
  if (!first.empty()) {
    hand_over(encode(first, info, meta.has_timecode, {}), meta, true);
    metrics_.encode.observe_ns(since_ns(encode_start));
  }
  if (!compressed_keys.empty() && compressed_) {
    const auto compressed_start = std::chrono::steady_clock::now();
    const subscriber::CompressedBlocks blocks = compressed_->encode(
        meta.frame_number, positions_, needs.compressed_normals ? std::span<const float>(normals_) : std::span<const float>(), compressed_blocks_);
    hand_over(encode(compressed_keys, info, meta.has_timecode, blocks), meta, first.empty());
    metrics_.encode_compressed.observe_ns(since_ns(compressed_start));
  }
}

// Every key of `keys` encoded into one pooled frame.
FrameRef Pipeline::encode(const StreamKeySet& keys, subscriber::FrameInfo info, bool has_timecode,
                          const subscriber::CompressedBlocks& compressed) {
  FrameRef ref = pool_.acquire();
  if (pool_.free_count() < kFreeFrames) pool_keeper_.wake();  // more made off this thread
  EncodedFrame& out = *ref.mutable_frame();
  out.frame_number = info.frame_number;
  out.model_epoch = options_.model_epoch;
  keys.for_each([&](StreamKey key) {
    const uint16_t version = stream_version(key);
    info.flags = stream_flags(key);
    info.vertex_count = vertex_count();
    if (version >= subscriber::kVersion2 && has_timecode) info.flags |= subscriber::kFrameTimecode;
    std::span<const unsigned char> block;
    if (info.flags & subscriber::kFrameParameters) {
      block = parameter_block_;
    } else if (info.flags & subscriber::kFrameCompressed) {
      if (compressed.key) info.flags |= subscriber::kFrameKey;
      const bool with_normals = info.flags & subscriber::kFrameNormals;
      block = std::span<const unsigned char>(compressed_blocks_).first(compressed.positions_bytes + (with_normals ? compressed.normals_bytes : 0));
    }
    const uint32_t markers = (info.flags & subscriber::kFrameMarkers) ? info.marker_count : 0;
    const bool coded = (info.flags & (subscriber::kFrameParameters | subscriber::kFrameCompressed)) != 0;
    const size_t bytes = coded ? subscriber::frame_message_bytes_with_block(block.size(), info.flags, markers)
                               : subscriber::frame_message_bytes(info.flags, (info.flags & subscriber::kFrameNoPositions) ? 0 : info.vertex_count,
                                                                 markers, version);
    if (pool_.size_message(out, key, bytes)) {  // first use of this encoding in this pooled frame, nothing prepared
      metrics_.frame_buffers_allocated.fetch_add(1, std::memory_order_relaxed);
      metrics_.frame_buffers_allocated_by_pipeline.fetch_add(1, std::memory_order_relaxed);
    }
    if (coded)
      subscriber::encode_frame_with_block(info, block, marker_floats_, marker_status_bytes_, out.messages[key]);
    else
      subscriber::encode_frame(info, positions_, normals_, marker_floats_, marker_status_bytes_, out.messages[key], version);
    out.encoded.add(key);
  });
  return ref;
}

// `first`: the frame's first hand-over, which counts it as published.
void Pipeline::hand_over(FrameRef ref, const Released& meta, bool first) {
  EncodedFrame& out = *ref.mutable_frame();
  // The publish time is taken last, so that publish - receive (in every frame's header) is the
  // daemon's whole processing, encoding included; delivery starts here.
  out.publish_time_ns = wall_clock_ns();
  out.published = std::chrono::steady_clock::now();
  out.encoded.for_each([&](StreamKey key) { subscriber::patch_publish_time(out.messages[key], out.publish_time_ns); });
  if (first) {
    metrics_.frames_dropped.store(mailbox_.dropped(), std::memory_order_relaxed);
    metrics_.frames_dropped_mailbox_full.store(mailbox_.dropped_mailbox_full(), std::memory_order_relaxed);
    // Counted before the hand-over, so that no reader of the counters (/health, the bench) can
    // find a subscriber holding a frame the count does not include yet: a publish thread may
    // write it out before this thread runs its next line.
    published_.fetch_add(1, std::memory_order_relaxed);
    metrics_.frames_published.fetch_add(1, std::memory_order_relaxed);
  }
  consumer_.publish(ref);
  if (first && meta.receive_time_ns > 0) {
    const int64_t processing = wall_clock_ns() - meta.receive_time_ns;
    metrics_.receive_to_publish.observe_ns(processing);
    if (meta.capture_latency_ns >= 0)
      metrics_.source_to_publish.observe_ns(meta.capture_latency_ns + processing);
  }
}

}  // namespace skinstream::server
