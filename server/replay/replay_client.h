#pragma once
// One TCP client of a replay server (the Vicon DataStream and QTM RT servers), whatever protocol
// it speaks: the packets waiting for it, written one at a time. Frames are bounded: with
// max_queued_frames waiting behind the one being written, a new frame pushes out the oldest
// waiting one (the newest wins, counted), so a slow client never delays the others; other
// packets (replies) are never dropped. A client is closed when it leaves, a write fails or it
// sends malformed input (counted and logged); its server then forgets it (replay_client_list.h).
// Each server held its own copy of this, and the copies had begun to differ.
//
// Threading: every member runs on the io_context's thread; the counters may be read from any.

#include <atomic>
#include <cstdint>
#include <deque>
#include <memory>
#include <string>
#include <vector>

#include "server/asio.h"
#include "server/logging.h"

namespace skinstream::server {

// What a server's clients share: its bound, its log and its counters. The server holds it and
// closes every client in stop(), so it outlives their use of it.
struct ReplayClientContext {
  std::string server_name;          // "vicon server": how the log lines begin
  std::string bad_client_category;  // of the rate-limited warning about malformed input
  size_t max_queued_frames;         // per client, frames waiting behind the one being written
  RateLimitedLog& log;
  std::atomic<uint64_t>& clients_open;
  std::atomic<uint64_t>& bad_clients;
  std::atomic<uint64_t>& frame_packets_sent;
  std::atomic<uint64_t>& frames_dropped;
};

class ReplayClient : public std::enable_shared_from_this<ReplayClient> {
 public:
  using Packet = std::shared_ptr<const std::vector<unsigned char>>;

  ReplayClient(tcp::socket socket, const ReplayClientContext& context);
  virtual ~ReplayClient() = default;
  ReplayClient(const ReplayClient&) = delete;
  ReplayClient& operator=(const ReplayClient&) = delete;

  // Queues a packet; a frame beyond the bound pushes out the oldest waiting frame.
  void enqueue(Packet packet, bool is_frame);
  // Malformed input: counted, logged and closed.
  void reject(const std::string& reason);
  void close();  // once; then closed()

  bool open() const { return open_; }
  bool idle() const { return queue_.empty() && !writing_; }  // nothing queued or being written
  size_t replies_waiting() const { return replies_waiting_; }  // queued packets that are not frames
  tcp::socket& socket() { return socket_; }
  const tcp::socket& socket() const { return socket_; }

 protected:
  // After a packet was written and the next one is on its way.
  virtual void after_write() {}
  // After close(): the server's part (forgetting the client, at least).
  virtual void closed() = 0;

 private:
  struct Outgoing {
    Packet packet;
    bool is_frame;
  };

  void write();
  void on_written(const boost::system::error_code& ec);

  tcp::socket socket_;
  const ReplayClientContext& context_;
  std::deque<Outgoing> queue_;  // front is being written while writing_
  size_t replies_waiting_ = 0;
  bool writing_ = false;
  bool open_ = true;
};

}  // namespace skinstream::server
