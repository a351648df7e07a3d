#include "server/publish/tcp_subscriber.h"

#include "server/publish/subscriber_hub.h"

namespace skinstream::server {

TcpSubscriber::TcpSubscriber(asio::io_context& io, SubscriberHub& hub, tcp::socket socket, std::string remote,
                             std::shared_ptr<const void> placement)
    : SubscriberSession(io, hub, "tcp", std::move(remote)), socket_(std::move(socket)), placement_(std::move(placement)) {}

void TcpSubscriber::start() {
  start_hello_timer(hub_->options().hello_timeout);
  read_next();
}

void TcpSubscriber::close() {
  boost::system::error_code ignored;
  socket_.shutdown(tcp::socket::shutdown_both, ignored);
  socket_.close(ignored);
  on_disconnected("closed by the daemon");
}

void TcpSubscriber::read_next() {
  socket_.async_read_some(asio::buffer(read_buffer_),
                          [self = std::static_pointer_cast<TcpSubscriber>(shared_from_this())](
                              const boost::system::error_code& ec, size_t n) {
                            if (ec) {
                              self->on_disconnected(ec == asio::error::eof ? "closed by the subscriber" : ec.message());
                              return;
                            }
                            try {
                              self->decoder_.feed(std::span(self->read_buffer_).first(n));
                              while (auto message = self->decoder_.next())
                                self->on_subscriber_message(message->type, message->payload, message->version);
                            } catch (const subscriber::DecodeError& e) {
                              self->on_protocol_error(e.what());
                              return;
                            }
                            self->read_next();
                          });
}

void TcpSubscriber::start_write(const std::array<asio::const_buffer, 2>& buffers) {
  asio::async_write(socket_, buffers, [self = shared_from_this(), this](const boost::system::error_code& ec, size_t) {
    write_done(ec);
  });
}

}  // namespace skinstream::server
