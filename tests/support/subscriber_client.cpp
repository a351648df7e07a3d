#include "support/subscriber_client.h"

#include <stdexcept>

namespace skinstream::sub {

std::pair<std::string, std::string> split_host_port(const std::string& address) {
  const size_t colon = address.rfind(':');
  if (colon == std::string::npos || colon == 0 || colon + 1 == address.size())
    throw std::invalid_argument("\"" + address + "\" is not HOST:PORT");
  return {address.substr(0, colon), address.substr(colon + 1)};
}

int64_t wall_clock_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
}

SubscriberClient::SubscriberClient(const std::string& host, const std::string& port, uint32_t wants)
    : SubscriberClient(host, port, subscriber::Hello{.wants = wants}) {}

SubscriberClient::SubscriberClient(const std::string& host, const std::string& port, const subscriber::Hello& hello) : socket_(io_) {
  server::tcp::resolver resolver(io_);
  boost::system::error_code ec;
  const auto endpoints = resolver.resolve(host, port, ec);
  if (ec) throw std::runtime_error(host + ":" + port + ": " + ec.message());
  server::asio::connect(socket_, endpoints, ec);
  if (ec) throw std::runtime_error(host + ":" + port + ": " + ec.message());
  socket_.set_option(server::tcp::no_delay(true));
  server::asio::write(socket_, server::asio::buffer(subscriber::encode_hello(hello)));
}

bool SubscriberClient::run(
    const std::function<bool(subscriber::MessageType, std::span<const unsigned char>, int64_t)>& on_message) {
  // Straight into the decoder, up to 1 MiB a read: a 53,500-vertex frame (640 kB) in one or two
  // reads, no copy on the way.
  constexpr size_t kReadBytes = 1 << 20;
  for (;;) {
    boost::system::error_code ec;
    const std::span<unsigned char> room = decoder_.prepare(kReadBytes);
    const size_t n = socket_.read_some(server::asio::buffer(room.data(), room.size()), ec);
    if (ec) return false;
    const int64_t now = wall_clock_ns();
    decoder_.commit(n);
    while (auto message = decoder_.next())
      if (!on_message(message->type, message->payload, now)) return true;
  }
}

}  // namespace skinstream::sub
