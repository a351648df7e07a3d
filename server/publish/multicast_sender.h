#pragma once
// Sends every frame's parameters once to a UDP multicast group (docs/subscriber-protocol.md,
// "Multicast"): one copy on the wire for any number of renderers on the LAN. It stands in front
// of the subscriber hub as the pipeline's consumer: it adds the parameter stream key to what the
// hub's subscribers want (so the pipeline fits the parts even when no TCP subscriber takes
// parameters), passes every frame on to the hub, then sends that key's message as datagrams.
//
// Called on the pipeline thread, so it never waits: the socket is non-blocking, the datagrams
// point into the pooled frame (one sendmmsg, no copy, no allocation), and a datagram the socket
// has no room for is dropped and counted (receivers lose that frame, nothing else). With a key,
// every datagram carries the HMAC-SHA-256 tag of its header and fragment
// (protocol/subscriber/datagram_authentication.h), so receivers given the key take no forged datagram.

#include <atomic>
#include <cstdint>
#include <span>
#include <memory>
#include <string>
#include <vector>
#include <sys/socket.h>
#include <sys/uio.h>

#include <nlohmann/json_fwd.hpp>

#include "protocol/subscriber/datagram_authentication.h"
#include "protocol/subscriber/multicast_datagram.h"
#include "server/logging.h"
#include "server/metrics/metrics.h"
#include "server/pipeline/pipeline.h"
#include "server/publish/multicast_group_socket.h"

namespace skinstream::server {

struct MulticastSenderOptions {
  MulticastGroupAddress frames;      // where every frame's datagrams go
  uint32_t stream_id = 0;            // the subject's stream
  std::vector<unsigned char> key{};  // the shared key (at least 16 bytes); empty: datagrams are not signed
  double offer_mbit = 0;             // the offer (MulticastOffer) to the next port at this rate; 0: none

  // Where the offer goes: the frames' group, the next port.
  MulticastGroupAddress offer_address() const {
    MulticastGroupAddress offer = frames;
    offer.port = static_cast<uint16_t>(frames.port + 1);
    return offer;
  }
};

class MulticastSender : public FrameConsumer {
 public:
  // The stream key whose messages are sent: version 2, parameters, no markers.
  static StreamKey sent_key();

  // Opens the socket; throws std::runtime_error with one line (a bad group or interface, no
  // socket). Nothing is sent before set_model().
  MulticastSender(FrameConsumer& next, const MulticastSenderOptions& options);
  ~MulticastSender() override;
  MulticastSender(const MulticastSender&) = delete;
  MulticastSender& operator=(const MulticastSender&) = delete;

  StreamKeySet wanted_encodings() const override;
  void publish(const FrameRef& frame) override;

  // Before the pipeline starts: the Model message's payload, whose CRC-32 every datagram carries
  // (the pipeline makes the Model, and needs its consumer first).
  void set_model(std::span<const unsigned char> model_payload);
  uint32_t model_id() const { return model_id_.load(std::memory_order_relaxed); }
  nlohmann::json health() const;           // /health's "multicast"
  void render_prometheus(std::string& out) const;  // appended to /metrics

 private:
  FrameConsumer& next_;
  MulticastSenderOptions options_;
  std::atomic<uint32_t> model_id_{0};  // read by /health while a swap sets it
  bool has_model_ = false;
  int fd_ = -1;
  uint32_t sequence_ = 0;  // pipeline thread only
  std::unique_ptr<subscriber::DatagramAuthenticator> authenticator_;  // with a key
  // One header, tag and three pieces (header, fragment, tag) per datagram, made once.
  unsigned char headers_[subscriber::kMaxFragments][subscriber::kDatagramHeaderBytes];
  subscriber::DatagramTag tags_[subscriber::kMaxFragments];
  iovec pieces_[3 * subscriber::kMaxFragments];
  mmsghdr datagrams_[subscriber::kMaxFragments];
  std::atomic<uint64_t> frames_sent_{0}, datagrams_sent_{0}, bytes_sent_{0};
  std::atomic<uint64_t> datagrams_dropped_{0};  // the socket buffer was full (EAGAIN, ENOBUFS)
  std::atomic<uint64_t> send_errors_{0};        // anything else (no route, ...): the frame's rest is dropped
  std::atomic<uint64_t> frames_too_large_{0};   // over 64 datagrams: never expected (a model of ~500 parts)
  LatencyHistogram send_time_;
  RateLimitedLog error_log_;
};

}  // namespace skinstream::server
