#pragma once
// The multicast offer (docs/subscriber-protocol.md, "The offer"): what a joining multicast
// receiver needs before its first frame (the packed MeshInfo of the parameter encoding and the
// packed Model, 0.84 MB for the demo body) sent round and round to the group's next port, at a
// fixed rate. Sixty render nodes that restart together then take one copy from the group instead
// of sixty over TCP; one that joins halfway through a round, or loses datagrams, takes what it
// lacks from the next round. A receiver that has the Model does not listen to that port.
//
// Its own thread paces the datagrams (a few every few ms), never the pipeline's. At each round's
// start it asks the subject for the messages: a new Model (a swap) or a new source rate is a new
// edition, whose number the datagrams carry. Signed with the frames' key, when there is one.

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "protocol/subscriber/datagram_authentication.h"
#include "server/logging.h"
#include "server/publish/multicast_sender.h"
#include "server/publish/subscriber_queue.h"

namespace skinstream::server {

class MulticastOffer {
 public:
  // What the offer carries now. Null messages: nothing to offer yet.
  struct Content {
    ControlMessage packed_mesh_info;  // version 2, the parameter encoding
    ControlMessage packed_model;
    ControlMessage model;  // plain: its payload's CRC-32 is the model id
  };
  using ContentSource = std::function<Content()>;

  // Opens the socket to options.offer_address(); throws std::runtime_error with one line. The
  // rate is options.offer_mbit (> 0). Sends nothing before start().
  MulticastOffer(const MulticastSenderOptions& options, ContentSource content);
  ~MulticastOffer();
  MulticastOffer(const MulticastOffer&) = delete;
  MulticastOffer& operator=(const MulticastOffer&) = delete;

  void start();
  void stop();  // safe to call twice

  nlohmann::json health() const;                   // /health's "multicast" "offer"
  void render_prometheus(std::string& out) const;  // appended to /metrics

 private:
  void run();
  // Makes the datagrams of `content` as a new edition (false: nothing to offer, or too large).
  bool make_edition(const Content& content);
  // Sends one round of the edition, paced; false when stopped meanwhile.
  bool send_round();
  // Waits until `when` or stop(); false when stopped.
  bool wait_until(std::chrono::steady_clock::time_point when);

  MulticastSenderOptions options_;
  ContentSource content_;
  int fd_ = -1;
  std::unique_ptr<subscriber::DatagramAuthenticator> authenticator_;
  RateLimitedLog error_log_;

  // The edition being offered (offer thread only).
  ControlMessage sent_mesh_info_, sent_model_;  // what it was made of
  std::vector<unsigned char> datagrams_;        // every datagram of a round, one after the other
  std::vector<size_t> datagram_ends_;

  std::atomic<uint32_t> edition_{0}, model_id_{0}, fragments_{0};
  std::atomic<uint64_t> offer_bytes_{0}, rounds_{0}, datagrams_sent_{0}, bytes_sent_{0},
      datagrams_dropped_{0}, send_errors_{0}, too_large_{0};

  std::mutex mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
  std::thread thread_;
};

}  // namespace skinstream::server
