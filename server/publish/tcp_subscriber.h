#pragma once
// A subscriber on the plain TCP port: reads its Hello from the byte stream, writes messages
// back to back.

#include <array>

#include "protocol/subscriber/subscriber_stream.h"
#include "server/publish/subscriber_session.h"

namespace skinstream::server {

class TcpSubscriber : public SubscriberSession {
 public:
  // `socket` must belong to `io`, the context all of this subscriber's handlers run on;
  // `placement` is kept for the subscriber's life (PublishThreads counts subscribers by it).
  TcpSubscriber(asio::io_context& io, SubscriberHub& hub, tcp::socket socket, std::string remote,
                std::shared_ptr<const void> placement = nullptr);
  void start();
  void close() override;

 private:
  void read_next();
  void start_write(const std::array<asio::const_buffer, 2>& buffers) override;
  void start_write_piece(asio::const_buffer piece, bool) override {
    start_write({piece, asio::const_buffer()});
  }

  tcp::socket socket_;
  std::shared_ptr<const void> placement_;
  std::array<unsigned char, 1024> read_buffer_{};
  subscriber::StreamDecoder decoder_{1024};  // subscribers only ever send a 4-byte Hello
};

}  // namespace skinstream::server
