#include "server/metrics/metrics.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace skinstream::server {
namespace {

void counter(std::string& out, const char* name, const char* help, uint64_t value) {
  out += "# HELP skinstream_" + std::string(name) + " " + help + "\n# TYPE skinstream_" + name + " counter\nskinstream_" +
         name + " " + std::to_string(value) + "\n";
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

double LatencyHistogram::quantile_upper_bound_ms(double q, uint64_t total, int64_t max_ns) const {
  const double max_ms = max_ns * 1e-6;
  // The rank of the quantile's observation, 1-based (nearest rank).
  const uint64_t rank = std::max<uint64_t>(1, static_cast<uint64_t>(std::ceil(q * static_cast<double>(total))));
  uint64_t cumulative = 0;
  for (size_t b = 0; b < kBounds.size(); ++b) {
    cumulative += buckets_[b].load(std::memory_order_relaxed);
    if (cumulative >= rank) return std::min(kBounds[b] * 1e3, max_ms);
  }
  return max_ms;  // beyond the last bound
}

LatencyHistogram::Summary LatencyHistogram::summary() const {
  Summary s;
  s.count = count_.load(std::memory_order_relaxed);
  if (s.count == 0) return s;
  const int64_t max_ns = max_ns_.load(std::memory_order_relaxed);
  s.max_ms = max_ns * 1e-6;
  s.p50_le_ms = quantile_upper_bound_ms(0.5, s.count, max_ns);
  s.p99_le_ms = quantile_upper_bound_ms(0.99, s.count, max_ns);
  s.p99_9_le_ms = quantile_upper_bound_ms(0.999, s.count, max_ns);
  return s;
}

void LatencyHistogram::render(std::string& out, std::string_view name, std::string_view help) const {
  const std::string n = "skinstream_" + std::string(name);
  out += "# HELP " + n + " " + std::string(help) + "\n# TYPE " + n + " histogram\n";
  uint64_t cumulative = 0;
  for (size_t b = 0; b < kBounds.size(); ++b) {
    cumulative += buckets_[b].load(std::memory_order_relaxed);
    out += n + "_bucket{le=\"" + number(kBounds[b]) + "\"} " + std::to_string(cumulative) + "\n";
  }
  const uint64_t total = count_.load(std::memory_order_relaxed);
  out += n + "_bucket{le=\"+Inf\"} " + std::to_string(total) + "\n";
  out += n + "_sum " + number(sum_ns_.load(std::memory_order_relaxed) * 1e-9) + "\n";
  out += n + "_count " + std::to_string(total) + "\n";
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

std::string Metrics::render_prometheus(const std::vector<SubscriberMetrics>& subscribers) const {
  std::string out;
  counter(out, "frames_received_total", "Marker frames received from the source.", frames_received);
  counter(out, "frames_processed_total", "Frames through the gap filler.", frames_processed);
  counter(out, "frames_published_total", "Frames handed to the publishers.", frames_published);
  counter(out, "frames_dropped_total", "Frames that gave way to newer ones in the mailbox (waited longer than max_frame_wait_ms, or a burst overfilled it).", frames_dropped);
  counter(out, "frames_dropped_mailbox_full_total", "Of the dropped frames, those of bursts longer than the mailbox holds.", frames_dropped_mailbox_full);
  counter(out, "markers_filled_total", "Marker samples filled (PCA, rigid or held).", markers_filled);
  counter(out, "markers_relabelled_total", "Marker samples taken from unlabelled points.", markers_relabelled);
  counter(out, "markers_held_total", "Marker samples held relative to their anchors.", markers_held);
  counter(out, "bad_subscriber_messages_total", "Subscriber messages that broke the protocol.", bad_subscriber_messages);
  counter(out, "subscribers_accepted_total", "Subscriber connections accepted.", subscribers_connected);
  counter(out, "subscribers_refused_total", "Subscribers refused after their Hello (unknown subject, ...).", subscribers_refused);
  counter(out, "subscribers_refused_not_allowed_total", "Subscribers refused as they connected: their address is in none of allow_subscribers.",
          subscribers_refused_not_allowed);
  counter(out, "subscribers_refused_limit_total",
          "Subscribers refused as they connected: max_subscribers or max_subscribers_per_address reached.", subscribers_refused_limit);
  counter(out, "subscribers_refused_token_total", "Subscribers refused for a missing or wrong subscriber_token.", subscribers_refused_token);
  counter(out, "subscribers_dropped_write_stall_total",
          "Subscribers closed because a write to them did not progress for subscriber_write_stall_ms.", subscribers_dropped_write_stall);
  counter(out, "accepts_failed_no_descriptor_total",
          "Accepts (HTTP and subscriber ports) that failed for lack of file descriptors; each pauses that port's accepts, 10 ms doubling to 1 s.",
          accepts_failed_no_descriptor);
  counter(out, "frame_buffers_allocated_total", "Encoded frame buffers created (steady state: constant).", frame_buffers_allocated);
  counter(out, "frame_buffers_allocated_by_pipeline_total",
          "Of those, created on the pipeline thread because none was prepared when the subscriber asked (expected: 0).",
          frame_buffers_allocated_by_pipeline);
  out += "# HELP skinstream_bad_input_total Source input dropped, by category.\n# TYPE skinstream_bad_input_total counter\n";
  {
    std::lock_guard lock(bad_input_mutex_);
    for (const auto& [category, count] : bad_input_)
      out += "skinstream_bad_input_total{category=\"" + label_value(category) + "\"} " + std::to_string(count) + "\n";
  }
  receive_to_take.render(out, "receive_to_take_seconds",
                         "From frame received to taken by the pipeline thread (the wait and the thread's wake-up).");
  fill.render(out, "fill_seconds", "Gap filler time per frame.");
  deform.render(out, "deform_seconds", "Mesh deformation time per frame (parts and vertices).");
  normals.render(out, "normals_seconds", "Normal computation time per frame.");
  encode.render(out, "encode_seconds", "Frame encoding time per frame (every encoding but the compressed one).");
  encode_compressed.render(out, "encode_compressed_seconds", "The compressed encoding's time per frame (vertex codec, after the other encodings were handed over).");
  receive_to_publish.render(out, "receive_to_publish_seconds", "From frame received to handed to the publishers.");
  subscriber_queue_wait.render(out, "subscriber_queue_wait_seconds",
                               "Per frame and subscriber: from published to its write starting (the subscriber's queue and its io thread's turn).");
  subscriber_write.render(out, "subscriber_write_seconds",
                          "Per frame and subscriber: from its write starting to the socket taking the last byte (longer when the subscriber reads slowly).");
  out += "# HELP skinstream_subscriber_frames_sent_total Frames written to each subscriber.\n"
         "# TYPE skinstream_subscriber_frames_sent_total counter\n";
  for (const SubscriberMetrics& s : subscribers)
    out += "skinstream_subscriber_frames_sent_total{id=\"" + std::to_string(s.id) + "\",transport=\"" + s.transport +
           "\",remote=\"" + label_value(s.remote) + "\"} " + std::to_string(s.sent) + "\n";
  out += "# HELP skinstream_subscriber_frames_dropped_total Frames dropped for each subscriber (waited longer than max_frame_wait_ms while a newer one was queued, or its queue was full).\n"
         "# TYPE skinstream_subscriber_frames_dropped_total counter\n";
  for (const SubscriberMetrics& s : subscribers)
    out += "skinstream_subscriber_frames_dropped_total{id=\"" + std::to_string(s.id) + "\",transport=\"" + s.transport +
           "\",remote=\"" + label_value(s.remote) + "\"} " + std::to_string(s.dropped) + "\n";
  out += "# HELP skinstream_subscribers Subscribers connected now.\n# TYPE skinstream_subscribers gauge\nskinstream_subscribers " +
         std::to_string(subscribers.size()) + "\n";
  return out;
}

}  // namespace skinstream::server
