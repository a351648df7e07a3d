#pragma once
// A subscriber on ws://HOST:PORT/stream: one protocol message per binary WebSocket message. A
// text message breaks the protocol: it is counted (bad_subscriber_messages) and the connection
// closed with WebSocket close code 1003.

#include "server/beast.h"
#include "server/publish/subscriber_session.h"

namespace skinstream::server {

class WebSocketSubscriber : public SubscriberSession {
 public:
  WebSocketSubscriber(asio::io_context& io, SubscriberHub& hub, tcp::socket socket, std::string remote);
  // Completes the upgrade the HTTP session read.
  void accept(http::request<http::string_body> request);
  void close() override;

 private:
  void read_next();
  void refuse_text_message();
  void start_write(const std::array<asio::const_buffer, 2>& buffers) override;
  void start_write_piece(asio::const_buffer piece, bool last) override;

  websocket::stream<beast::tcp_stream> ws_;
  beast::flat_buffer read_buffer_;
};

}  // namespace skinstream::server
