#include "server/publish/multicast_sender.h"

#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <nlohmann/json.hpp>
#include <stdexcept>

namespace skinstream::server {
namespace {

namespace wire = skinstream::subscriber;

std::string where(const MulticastSenderOptions& o) { return describe(o.frames); }

}  // namespace

StreamKey MulticastSender::sent_key() { return stream_key(wire::kFrameParameters, wire::kVersion2); }

MulticastSender::MulticastSender(FrameConsumer& next, const MulticastSenderOptions& options) : next_(next), options_(options) {
  fd_ = open_multicast_group_socket(options.frames);
  if (!options.key.empty()) {
    try {
      authenticator_ = std::make_unique<wire::DatagramAuthenticator>(options.key);
    } catch (const std::invalid_argument& e) {
      close(fd_);
      throw std::runtime_error(where(options) + ": " + e.what());
    }
  }
  std::memset(datagrams_, 0, sizeof datagrams_);
  for (int i = 0; i < wire::kMaxFragments; ++i) {
    pieces_[3 * i] = {headers_[i], wire::kDatagramHeaderBytes};
    pieces_[3 * i + 2] = {tags_[i].data(), tags_[i].size()};
    datagrams_[i].msg_hdr.msg_iov = &pieces_[3 * i];
    datagrams_[i].msg_hdr.msg_iovlen = authenticator_ ? 3 : 2;
  }
}

MulticastSender::~MulticastSender() {
  if (fd_ >= 0) close(fd_);
}

void MulticastSender::set_model(std::span<const unsigned char> model_payload) {
  model_id_ = wire::model_id_of(model_payload);
  has_model_ = true;
}

StreamKeySet MulticastSender::wanted_encodings() const {
  StreamKeySet keys = next_.wanted_encodings();
  keys.add(sent_key());
  return keys;
}

void MulticastSender::publish(const FrameRef& frame) {
  next_.publish(frame);
  if (!has_model_ || !frame->has(sent_key())) return;  // no Model yet; or a later hand-over of the frame (compressed)
  const auto start = std::chrono::steady_clock::now();
  const std::span<const unsigned char> message = frame->message(sent_key());
  const bool signed_datagrams = authenticator_ != nullptr;
  const uint16_t count = wire::fragment_count(message.size(), signed_datagrams);
  if (count == 0) {
    frames_too_large_.fetch_add(1, std::memory_order_relaxed);
    error_log_.warn("too_large", where(options_) + ": a frame of " + std::to_string(message.size()) + " bytes is over the " +
                                     std::to_string(signed_datagrams ? wire::kMaxAuthenticatedMessageBytes : wire::kMaxDatagramMessageBytes) +
                                     " 64 datagrams carry; not sent");
    return;
  }
  wire::DatagramHeader header{options_.stream_id,
                              model_id_.load(std::memory_order_relaxed),
                              sequence_++,
                              0,
                              count,
                              static_cast<uint32_t>(message.size()),
                              signed_datagrams};
  for (uint16_t i = 0; i < count; ++i) {
    header.index = i;
    wire::encode_datagram_header(header, headers_[i]);
    const std::span<const unsigned char> fragment =
        message.subspan(wire::fragment_offset(message.size(), count, i), wire::fragment_bytes(message.size(), count, i));
    // sendmmsg only reads the fragment; iovec has no const.
    pieces_[3 * i + 1] = {const_cast<unsigned char*>(fragment.data()), fragment.size()};
    if (signed_datagrams) {
      const std::span<const unsigned char> parts[] = {headers_[i], fragment};
      tags_[i] = authenticator_->tag(parts);
    }
  }
  const GroupSend send = send_to_group(fd_, datagrams_, count);
  const size_t sent = send.sent;
  if (send.buffer_full) datagrams_dropped_.fetch_add(count - sent, std::memory_order_relaxed);
  if (send.error != 0) {
    send_errors_.fetch_add(1, std::memory_order_relaxed);
    error_log_.warn("send", where(options_) + ": send failed: " + std::strerror(send.error) +
                                "; the frame's other datagrams are dropped");
  }
  if (sent == count) frames_sent_.fetch_add(1, std::memory_order_relaxed);
  datagrams_sent_.fetch_add(static_cast<uint64_t>(sent), std::memory_order_relaxed);
  uint64_t bytes = 0;
  for (size_t i = 0; i < sent; ++i)
    bytes += wire::kDatagramHeaderBytes + pieces_[3 * i + 1].iov_len + (signed_datagrams ? wire::kDatagramTagBytes : 0);
  bytes_sent_.fetch_add(bytes, std::memory_order_relaxed);
  send_time_.observe_ns(std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - start).count());
}

nlohmann::json MulticastSender::health() const {
  const LatencyHistogram::Summary send = send_time_.summary();
  return {{"group", options_.frames.group},
          {"port", options_.frames.port},
          {"interface", options_.frames.interface_address},
          {"ttl", options_.frames.ttl},
          {"stream_id", options_.stream_id},
          {"authenticated", authenticator_ != nullptr},
          {"model_id", model_id_.load()},
          {"frames_sent", frames_sent_.load()},
          {"datagrams_sent", datagrams_sent_.load()},
          {"bytes_sent", bytes_sent_.load()},
          {"datagrams_dropped", datagrams_dropped_.load()},
          {"send_errors", send_errors_.load()},
          {"frames_too_large", frames_too_large_.load()},
          {"send_ms",
           {{"count", send.count},
            {"p50_le", send.p50_le_ms},
            {"p99_le", send.p99_le_ms},
            {"max", send.max_ms}}}};
}

void MulticastSender::render_prometheus(std::string& out) const {
  const struct {
    const char* name;
    const char* help;
    const std::atomic<uint64_t>& value;
  } counters[] = {
      {"multicast_frames_sent_total", "Frames whose every datagram went to the multicast group.", frames_sent_},
      {"multicast_datagrams_sent_total", "Multicast datagrams sent.", datagrams_sent_},
      {"multicast_bytes_sent_total", "UDP payload bytes sent to the multicast group.", bytes_sent_},
      {"multicast_datagrams_dropped_total", "Multicast datagrams dropped because the socket buffer was full.", datagrams_dropped_},
      {"multicast_send_errors_total", "Failed multicast sends (each drops the rest of its frame).", send_errors_},
      {"multicast_frames_too_large_total", "Frames over 64 datagrams, not sent.", frames_too_large_},
  };
  for (const auto& c : counters) render_counter(out, c.name, c.help, c.value.load(std::memory_order_relaxed));
  send_time_.render(out, "multicast_send_seconds", "Time per frame to hand its datagrams to the socket (pipeline thread).");
}

}  // namespace skinstream::server
