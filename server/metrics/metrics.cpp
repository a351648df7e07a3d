#include "server/metrics/metrics.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace skinstream::server {

namespace {

void header(std::string& out, std::string_view name, std::string_view help, std::string_view type) {
  const std::string n = "skinstream_" + std::string(name);
  out += "# HELP " + n + " " + std::string(help) + "\n# TYPE " + n + " " + std::string(type) + "\n";
}

// Prometheus label values escape backslash, quote and newline.
std::string label_value(std::string_view v) {
  std::string out;
  for (char c : v) {
    if (c == '\\' || c == '"') out += '\\', out += c;
    else if (c == '\n') out += "\\n";
    else out += c;
  }
  return out;
}

std::string number(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.9g", v);
  return text;
}

}  // namespace

void render_counter(std::string& out, std::string_view name, std::string_view help, uint64_t value) {
  header(out, name, help, "counter");
  out += "skinstream_" + std::string(name) + " " + std::to_string(value) + "\n";
}

void LatencyHistogram::observe_ns(int64_t ns) {
  const double seconds = ns * 1e-9;
  size_t b = 0;
  while (b < kBounds.size() && seconds > kBounds[b]) ++b;
  if (b < kBounds.size()) buckets_[b].fetch_add(1, std::memory_order_relaxed);
  count_.fetch_add(1, std::memory_order_relaxed);
  sum_ns_.fetch_add(ns, std::memory_order_relaxed);
  for (int64_t seen = max_ns_.load(std::memory_order_relaxed);
       ns > seen && !max_ns_.compare_exchange_weak(seen, ns, std::memory_order_relaxed);) {
  }
}

double LatencyHistogram::quantile_upper_bound_ms(const Buckets& counts, uint64_t total, double q, double beyond_ms) {
  // The rank of the quantile's observation, 1-based (nearest rank).
  const uint64_t rank = std::max<uint64_t>(1, static_cast<uint64_t>(std::ceil(q * static_cast<double>(total))));
  uint64_t cumulative = 0;
  for (size_t b = 0; b < kBounds.size(); ++b) {
    cumulative += counts[b];
    if (cumulative >= rank) return kBounds[b] * 1e3;
  }
  return beyond_ms;
}

LatencyHistogram::Buckets LatencyHistogram::bucket_counts() const {
  Buckets counts;
  for (size_t b = 0; b < kBounds.size(); ++b) counts[b] = buckets_[b].load(std::memory_order_relaxed);
  return counts;
}

LatencyHistogram::Summary LatencyHistogram::summary() const {
  Summary s;
  s.count = count_.load(std::memory_order_relaxed);
  if (s.count == 0) return s;
  s.max_ms = max_ns_.load(std::memory_order_relaxed) * 1e-6;
  // The largest value observed also bounds each quantile, within the buckets or beyond them.
  const Buckets counts = bucket_counts();
  s.p50_le_ms = std::min(quantile_upper_bound_ms(counts, s.count, 0.5, s.max_ms), s.max_ms);
  s.p99_le_ms = std::min(quantile_upper_bound_ms(counts, s.count, 0.99, s.max_ms), s.max_ms);
  s.p99_9_le_ms = std::min(quantile_upper_bound_ms(counts, s.count, 0.999, s.max_ms), s.max_ms);
  return s;
}

void LatencyHistogram::render(std::string& out, std::string_view name, std::string_view help) const {
  header(out, name, help, "histogram");
  render_samples(out, name, "");
}

void LatencyHistogram::render_samples(std::string& out, std::string_view name, std::string_view labels) const {
  const std::string n = "skinstream_" + std::string(name);
  const std::string before = labels.empty() ? std::string() : std::string(labels) + ",";
  uint64_t cumulative = 0;
  for (size_t b = 0; b < kBounds.size(); ++b) {
    cumulative += buckets_[b].load(std::memory_order_relaxed);
    out += n + "_bucket{" + before + "le=\"" + number(kBounds[b]) + "\"} " + std::to_string(cumulative) + "\n";
  }
  const uint64_t total = count_.load(std::memory_order_relaxed);
  const std::string own = labels.empty() ? std::string() : "{" + std::string(labels) + "}";
  out += n + "_bucket{" + before + "le=\"+Inf\"} " + std::to_string(total) + "\n";
  out += n + "_sum" + own + " " + number(sum_ns_.load(std::memory_order_relaxed) * 1e-9) + "\n";
  out += n + "_count" + own + " " + std::to_string(total) + "\n";
}

void Metrics::count_bad_input(std::string_view category) {
  std::lock_guard lock(bad_input_mutex_);
  auto it = bad_input_.find(category);
  if (it == bad_input_.end()) it = bad_input_.emplace(std::string(category), 0).first;
  ++it->second;
}

uint64_t Metrics::bad_input(std::string_view category) const {
  std::lock_guard lock(bad_input_mutex_);
  const auto it = bad_input_.find(category);
  return it == bad_input_.end() ? 0 : it->second;
}

std::map<std::string, uint64_t, std::less<>> Metrics::bad_input_counts() const {
  std::lock_guard lock(bad_input_mutex_);
  return bad_input_;
}

std::string render_prometheus(const Metrics& source, const std::vector<SubjectMetricsView>& subjects) {
  std::string out;
  std::vector<std::string> labels;  // subject="NAME", per subject
  for (const SubjectMetricsView& s : subjects) labels.push_back("subject=\"" + label_value(s.subject) + "\"");
  // A counter of every subject, read from its Metrics.
  auto per_subject = [&](const char* name, const char* help, const std::atomic<uint64_t> Metrics::*field) {
    header(out, name, help, "counter");
    for (size_t i = 0; i < subjects.size(); ++i)
      out += "skinstream_" + std::string(name) + "{" + labels[i] + "} " + std::to_string((subjects[i].metrics->*field).load()) + "\n";
  };
  header(out, "source_frames_total", "Frames received from the source (every subject's together).", "counter");
  out += "skinstream_source_frames_total " + std::to_string(source.frames_received.load()) + "\n";
  header(out, "source_frames_skipped_total",
         "Frame numbers the source skipped: frames it numbered and never delivered (lost on the way, or skipped for a slow reader).",
         "counter");
  out += "skinstream_source_frames_skipped_total " + std::to_string(source.source_frames_skipped.load()) + "\n";
  header(out, "source_renumberings_total", "Frames whose number continued nothing before it (the source restarted, a replay looped).",
         "counter");
  out += "skinstream_source_renumberings_total " + std::to_string(source.source_renumberings.load()) + "\n";
  header(out, "accepts_failed_no_descriptor_total",
         "Accepts (HTTP and subscriber ports) that failed for lack of file descriptors; each pauses that port's accepts, 10 ms doubling to 1 s.",
         "counter");
  out += "skinstream_accepts_failed_no_descriptor_total " + std::to_string(source.accepts_failed_no_descriptor.load()) + "\n";
  // Who may subscribe is decided for the whole daemon, as a subscriber connects (before it names a subject).
  auto daemon_counter = [&](const char* name, const char* help, const std::atomic<uint64_t>& value) {
    header(out, name, help, "counter");
    out += "skinstream_" + std::string(name) + " " + std::to_string(value.load()) + "\n";
  };
  daemon_counter("subscribers_refused_not_allowed_total", "Subscribers refused as they connected: their address is in none of allow_subscribers.",
                 source.subscribers_refused_not_allowed);
  daemon_counter("subscribers_refused_limit_total", "Subscribers refused as they connected: max_subscribers or max_subscribers_per_address reached.",
                 source.subscribers_refused_limit);
  daemon_counter("subscribers_refused_token_total", "Subscribers refused for a missing or wrong subscriber_token.", source.subscribers_refused_token);
  daemon_counter("subscribers_refused_unauthenticated_total",
                 "Connections refused as they connected: too many without the subscriber_token yet (max_unauthenticated_subscribers, "
                 "max_unauthenticated_per_address).",
                 source.subscribers_refused_unauthenticated);
  per_subject("frames_received_total", "Marker frames of the subject received from the source.", &Metrics::frames_received);
  per_subject("frames_processed_total", "Frames through the gap filler.", &Metrics::frames_processed);
  per_subject("frames_published_total", "Frames handed to the publishers.", &Metrics::frames_published);
  per_subject("frames_dropped_total", "Frames that gave way to newer ones in the mailbox (waited longer than max_frame_wait_ms, or a burst overfilled it).", &Metrics::frames_dropped);
  per_subject("frames_dropped_mailbox_full_total", "Of the dropped frames, those of bursts longer than the mailbox holds.", &Metrics::frames_dropped_mailbox_full);
  per_subject("markers_filled_total", "Marker samples filled (PCA, rigid or held).", &Metrics::markers_filled);
  per_subject("markers_relabelled_total", "Marker samples taken from unlabelled points.", &Metrics::markers_relabelled);
  per_subject("markers_held_total", "Marker samples held relative to their anchors.", &Metrics::markers_held);
  per_subject("source_rate_changes_total", "Times the gap filler was rebuilt for a new source rate (the rate became known, or changed by more than 0.1%).",
              &Metrics::source_rate_changes);
  per_subject("bad_subscriber_messages_total", "Subscriber messages that broke the protocol.", &Metrics::bad_subscriber_messages);
  per_subject("subscribers_accepted_total", "Subscriber connections accepted.", &Metrics::subscribers_connected);
  per_subject("subscribers_refused_total", "Subscribers refused after their Hello (unknown subject, ...).", &Metrics::subscribers_refused);
  per_subject("subscribers_dropped_write_stall_total", "Subscribers closed because a write to them did not progress for subscriber_write_stall_ms.",
              &Metrics::subscribers_dropped_write_stall);
  per_subject("frame_buffers_allocated_total", "Encoded frame buffers created (steady state: constant; more when a released encoding is asked for again).", &Metrics::frame_buffers_allocated);
  per_subject("frame_buffers_allocated_by_pipeline_total",
              "Of those, created on the pipeline thread because none was prepared when the subscriber asked (expected: 0).",
              &Metrics::frame_buffers_allocated_by_pipeline);
  per_subject("frame_buffers_released_total", "Encoded frame buffers freed because no subscriber wanted their encoding any more.",
              &Metrics::frame_buffers_released);
  header(out, "bad_input_total", "Input dropped, by category: the source's without a subject label, a subject's pipeline's with one.", "counter");
  for (const auto& [category, count] : source.bad_input_counts())
    out += "skinstream_bad_input_total{category=\"" + label_value(category) + "\"} " + std::to_string(count) + "\n";
  for (size_t i = 0; i < subjects.size(); ++i)
    for (const auto& [category, count] : subjects[i].metrics->bad_input_counts())
      out += "skinstream_bad_input_total{" + labels[i] + ",category=\"" + label_value(category) + "\"} " + std::to_string(count) + "\n";
  auto histogram = [&](const char* name, const char* help, const LatencyHistogram Metrics::*field) {
    header(out, name, help, "histogram");
    for (size_t i = 0; i < subjects.size(); ++i) (subjects[i].metrics->*field).render_samples(out, name, labels[i]);
  };
  histogram("receive_to_take_seconds", "From frame received to taken by the pipeline thread (the wait and the thread's wake-up).", &Metrics::receive_to_take);
  histogram("fill_seconds", "Gap filler time per frame.", &Metrics::fill);
  histogram("deform_seconds", "Mesh deformation time per frame (parts and vertices).", &Metrics::deform);
  histogram("normals_seconds", "Normal computation time per frame.", &Metrics::normals);
  histogram("encode_seconds", "Frame encoding time per frame (every encoding but the compressed one).", &Metrics::encode);
  histogram("encode_compressed_seconds", "The compressed encoding's time per frame (vertex codec, after the other encodings were handed over).",
            &Metrics::encode_compressed);
  histogram("receive_to_publish_seconds", "From frame received to handed to the publishers.", &Metrics::receive_to_publish);
  histogram("source_to_publish_seconds",
            "From the cameras' exposure to handed to the publishers, where the capture system reports its "
            "own latency "
            "(NatNet): its latency plus receive_to_publish; the network between is not in it.",
            &Metrics::source_to_publish);
  histogram("subscriber_queue_wait_seconds",
            "Per frame and subscriber: from published to its write starting (the subscriber's queue and its io thread's turn).",
            &Metrics::subscriber_queue_wait);
  histogram("subscriber_write_seconds",
            "Per frame and subscriber: from its write starting to the socket taking the last byte (longer when the subscriber reads slowly).",
            &Metrics::subscriber_write);
  auto per_subscriber = [&](const char* name, const char* help, uint64_t SubscriberMetrics::*field) {
    header(out, name, help, "counter");
    for (size_t i = 0; i < subjects.size(); ++i)
      for (const SubscriberMetrics& s : subjects[i].subscribers)
        out += "skinstream_" + std::string(name) + "{" + labels[i] + ",id=\"" + std::to_string(s.id) + "\",transport=\"" + s.transport +
               "\",remote=\"" + label_value(s.remote) + "\"} " + std::to_string(s.*field) + "\n";
  };
  per_subscriber("subscriber_frames_sent_total", "Frames written to each subscriber.", &SubscriberMetrics::sent);
  per_subscriber("subscriber_frames_dropped_total",
                 "Frames dropped for each subscriber (waited longer than max_frame_wait_ms while a newer one was queued, or its queue was full).",
                 &SubscriberMetrics::dropped);
  header(out, "subscribers", "Subscribers connected now.", "gauge");
  for (size_t i = 0; i < subjects.size(); ++i)
    out += "skinstream_subscribers{" + labels[i] + "} " + std::to_string(subjects[i].subscribers.size()) + "\n";
  return out;
}

}  // namespace skinstream::server
