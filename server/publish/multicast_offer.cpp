#include "server/publish/multicast_offer.h"

#include <sys/socket.h>
#include <sys/uio.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "protocol/subscriber/multicast_datagram.h"
#include "protocol/subscriber/offer_content.h"
#include "server/thread_name.h"

namespace skinstream::server {
namespace {

namespace wire = skinstream::subscriber;

// Datagrams handed to the socket at once: at 20 Mbit/s a batch every 4.5 ms.
constexpr size_t kBatch = 8;

std::span<const unsigned char> payload_of(const std::vector<unsigned char>& message) {
  return std::span<const unsigned char>(message).subspan(wire::kHeaderBytes);
}

}  // namespace

MulticastOffer::MulticastOffer(const MulticastSenderOptions& options, ContentSource content)
    : options_(options), content_(std::move(content)) {
  if (!(options.offer_mbit > 0))
    throw std::runtime_error(describe(options.offer_address()) + ": the offer's rate must be above 0 Mbit/s");
  if (options.frames.port == 65535)
    throw std::runtime_error(describe(options.frames) +
                             ": the offer goes to the next port, and there is none");
  fd_ = open_multicast_group_socket(options.offer_address());
  if (!options.key.empty()) {
    try {
      authenticator_ = std::make_unique<wire::DatagramAuthenticator>(options.key);
    } catch (const std::invalid_argument& e) {
      close(fd_);
      throw std::runtime_error(describe(options.offer_address()) + ": " + e.what());
    }
  }
}

MulticastOffer::~MulticastOffer() {
  stop();
  if (fd_ >= 0) close(fd_);
}

void MulticastOffer::start() {
  if (thread_.joinable()) return;
  thread_ = std::thread([this] {
    name_this_thread("offer");
    run();
  });
}

void MulticastOffer::stop() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

bool MulticastOffer::wait_until(std::chrono::steady_clock::time_point when) {
  std::unique_lock lock(mutex_);
  wake_.wait_until(lock, when, [this] { return stopping_; });
  return !stopping_;
}

void MulticastOffer::run() {
  bool has_edition = false;
  for (;;) {
    // Made again only when the messages change: an offer too large stays so until then.
    const Content content = content_();
    if (content.packed_mesh_info != sent_mesh_info_ || content.packed_model != sent_model_)
      has_edition = make_edition(content);
    if (!has_edition) {
      if (!wait_until(std::chrono::steady_clock::now() + std::chrono::seconds(1))) return;
      continue;
    }
    if (!send_round()) return;
  }
}

bool MulticastOffer::make_edition(const Content& content) {
  sent_mesh_info_ = content.packed_mesh_info;
  sent_model_ = content.packed_model;
  if (!content.packed_mesh_info || !content.packed_model || !content.model) return false;
  const std::vector<unsigned char> offer =
      wire::encode_offer(*content.packed_mesh_info, *content.packed_model);
  const bool signed_datagrams = authenticator_ != nullptr;
  const uint16_t count = wire::fragment_count(offer.size(), signed_datagrams, wire::kMaxOfferFragments);
  if (count == 0) {
    too_large_.fetch_add(1, std::memory_order_relaxed);
    error_log_.warn("too_large", describe(options_.offer_address()) + ": an offer of " +
                                     std::to_string(offer.size()) + " bytes is over what " +
                                     std::to_string(wire::kMaxOfferFragments) +
                                     " datagrams carry; not offered (receivers fetch the Model over TCP)");
    return false;
  }
  const uint32_t edition =
      edition_.load(std::memory_order_relaxed) + (offer_bytes_.load(std::memory_order_relaxed) > 0 ? 1 : 0);
  const wire::DatagramHeader header{options_.stream_id,
                                    wire::model_id_of(payload_of(*content.model)),
                                    edition,
                                    0,
                                    count,
                                    static_cast<uint32_t>(offer.size()),
                                    signed_datagrams,
                                    true};
  // Every datagram of the round made once per edition (the tags too): a round then only sends.
  datagrams_.clear();
  datagram_ends_.clear();
  for (uint16_t i = 0; i < count; ++i) {
    wire::DatagramHeader h = header;
    h.index = i;
    const size_t start = datagrams_.size();
    datagrams_.resize(start + wire::kDatagramHeaderBytes);
    wire::encode_datagram_header(h, std::span<unsigned char, wire::kDatagramHeaderBytes>(
                                        datagrams_.data() + start, wire::kDatagramHeaderBytes));
    const auto fragment = std::span<const unsigned char>(offer).subspan(
        wire::fragment_offset(offer.size(), count, i), wire::fragment_bytes(offer.size(), count, i));
    datagrams_.insert(datagrams_.end(), fragment.begin(), fragment.end());
    if (authenticator_) {
      const std::span<const unsigned char> parts[] = {
          std::span<const unsigned char>(datagrams_).subspan(start)};
      const wire::DatagramTag tag = authenticator_->tag(parts);
      datagrams_.insert(datagrams_.end(), tag.begin(), tag.end());
    }
    datagram_ends_.push_back(datagrams_.size());
  }
  edition_.store(edition, std::memory_order_relaxed);
  model_id_.store(header.model_id, std::memory_order_relaxed);
  fragments_.store(count, std::memory_order_relaxed);
  offer_bytes_.store(offer.size(), std::memory_order_relaxed);
  return true;
}

bool MulticastOffer::send_round() {
  const double bytes_per_second = options_.offer_mbit * 1e6 / 8;
  auto next = std::chrono::steady_clock::now();
  iovec pieces[kBatch];
  mmsghdr batch[kBatch];
  for (size_t first = 0; first < datagram_ends_.size(); first += kBatch) {
    const size_t n = std::min(kBatch, datagram_ends_.size() - first);
    size_t bytes = 0;  // of the batch: its pacing
    std::memset(batch, 0, sizeof batch);
    for (size_t k = 0; k < n; ++k) {
      const size_t begin = first + k == 0 ? 0 : datagram_ends_[first + k - 1];
      pieces[k] = {datagrams_.data() + begin, datagram_ends_[first + k] - begin};
      batch[k].msg_hdr.msg_iov = &pieces[k];
      batch[k].msg_hdr.msg_iovlen = 1;
      bytes += pieces[k].iov_len;
    }
    const GroupSend send = send_to_group(fd_, batch, n);
    if (send.buffer_full)
      datagrams_dropped_.fetch_add(n - send.sent, std::memory_order_relaxed);  // the next round brings them
    if (send.error != 0) {
      send_errors_.fetch_add(1, std::memory_order_relaxed);
      error_log_.warn("send",
                      describe(options_.offer_address()) + ": send failed: " + std::strerror(send.error));
    }
    datagrams_sent_.fetch_add(send.sent, std::memory_order_relaxed);
    uint64_t bytes_sent = 0;  // of the datagrams the socket took
    for (size_t k = 0; k < send.sent; ++k) bytes_sent += pieces[k].iov_len;
    bytes_sent_.fetch_add(bytes_sent, std::memory_order_relaxed);
    if (first + n == datagram_ends_.size()) rounds_.fetch_add(1, std::memory_order_relaxed);
    next += std::chrono::duration_cast<std::chrono::steady_clock::duration>(
        std::chrono::duration<double>(bytes / bytes_per_second));
    if (!wait_until(next)) return false;
  }
  return true;
}

nlohmann::json MulticastOffer::health() const {
  return {{"port", options_.offer_address().port},
          {"mbit", options_.offer_mbit},
          {"edition", edition_.load()},
          {"model_id", model_id_.load()},
          {"bytes", offer_bytes_.load()},
          {"datagrams_per_round", fragments_.load()},
          {"rounds", rounds_.load()},
          {"datagrams_sent", datagrams_sent_.load()},
          {"bytes_sent", bytes_sent_.load()},
          {"datagrams_dropped", datagrams_dropped_.load()},
          {"send_errors", send_errors_.load()},
          {"too_large", too_large_.load()}};
}

void MulticastOffer::render_prometheus(std::string& out) const {
  const struct {
    const char* name;
    const char* help;
    const std::atomic<uint64_t>& value;
  } counters[] = {
      {"multicast_offer_rounds_total", "Rounds of the offer (packed MeshInfo and Model) sent to the group.",
       rounds_},
      {"multicast_offer_datagrams_sent_total", "Datagrams of the offer sent.", datagrams_sent_},
      {"multicast_offer_bytes_sent_total", "UDP payload bytes of the offer sent.", bytes_sent_},
      {"multicast_offer_datagrams_dropped_total",
       "Datagrams of the offer dropped because the socket buffer was full.", datagrams_dropped_},
      {"multicast_offer_send_errors_total", "Failed sends of the offer.", send_errors_},
  };
  for (const auto& c : counters) render_counter(out, c.name, c.help, c.value.load(std::memory_order_relaxed));
}

}  // namespace skinstream::server
