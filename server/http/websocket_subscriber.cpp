#include "server/http/websocket_subscriber.h"

#include <spdlog/spdlog.h>

#include "protocol/subscriber/subscriber_stream.h"
#include "server/publish/subscriber_hub.h"

namespace skinstream::server {

WebSocketSubscriber::WebSocketSubscriber(asio::io_context& io, SubscriberHub& hub, tcp::socket socket, std::string remote)
    : SubscriberSession(io, hub, "websocket", std::move(remote)), ws_(std::move(socket)) {}

void WebSocketSubscriber::accept(http::request<http::string_body> request) {
  ws_.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
  ws_.read_message_max(1024);  // subscribers only send Hello
  ws_.binary(true);
  ws_.async_accept(request, [self = std::static_pointer_cast<WebSocketSubscriber>(shared_from_this())](
                                const boost::system::error_code& ec) {
    if (ec) {
      self->on_disconnected("WebSocket handshake failed: " + ec.message());
      return;
    }
    self->start_hello_timer(self->hub_->options().hello_timeout);
    self->read_next();
  });
}

void WebSocketSubscriber::close() {
  boost::system::error_code ignored;
  beast::get_lowest_layer(ws_).socket().shutdown(tcp::socket::shutdown_both, ignored);
  beast::get_lowest_layer(ws_).socket().close(ignored);
  on_disconnected("closed by the daemon");
}

void WebSocketSubscriber::read_next() {
  ws_.async_read(read_buffer_, [self = std::static_pointer_cast<WebSocketSubscriber>(shared_from_this())](
                                   const boost::system::error_code& ec, size_t) {
    if (ec) {
      self->on_disconnected(ec == websocket::error::closed ? "closed by the subscriber" : ec.message());
      return;
    }
    if (!self->ws_.got_binary()) return self->refuse_text_message();
    const auto data = self->read_buffer_.cdata();
    const std::span<const unsigned char> bytes(static_cast<const unsigned char*>(data.data()), data.size());
    try {
      const subscriber::MessageHeader header = subscriber::decode_header(bytes, 1024);
      if (header.payload_bytes != bytes.size() - subscriber::kHeaderBytes)
        throw subscriber::DecodeError("WebSocket message is not exactly one protocol message");
      self->on_subscriber_message(header.type, bytes.subspan(subscriber::kHeaderBytes), header.version);
    } catch (const subscriber::DecodeError& e) {
      self->on_protocol_error(e.what());
      return;
    }
    self->read_buffer_.consume(self->read_buffer_.size());
    self->read_next();
  });
}

void WebSocketSubscriber::refuse_text_message() {
  hub_->metrics().bad_subscriber_messages.fetch_add(1, std::memory_order_relaxed);
  spdlog::warn("subscriber {} (websocket {}): a text message; the subscriber protocol is binary only; closing", id(),
               stats().remote);
  // Closed with a reason (1003, data of a kind the daemon does not take) the peer's WebSocket API
  // shows, then the socket; a peer that never answers the close is cut by the handshake timeout.
  ws_.async_close(websocket::close_reason(websocket::close_code::unknown_data, "binary messages only"),
                  [self = shared_from_this()](const boost::system::error_code&) { self->close(); });
}

void WebSocketSubscriber::start_write(const std::array<asio::const_buffer, 2>& buffers) {
  ws_.async_write(buffers, [self = shared_from_this(), this](const boost::system::error_code& ec, size_t) { write_done(ec); });
}

void WebSocketSubscriber::start_write_piece(asio::const_buffer piece, bool last) {
  ws_.async_write_some(
      last, piece,
      [self = shared_from_this(), this](const boost::system::error_code& ec, size_t) { write_done(ec); });
}

}  // namespace skinstream::server
