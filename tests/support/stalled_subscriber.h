#pragma once
// A subscriber that sends its Hello and then never reads, with a tiny receive buffer: whatever
// the daemon sends it backs up at once, as behind a stuck renderer.
#include <vector>

#include "server/asio.h"

namespace skinstream::test {

inline server::tcp::socket stalled_subscriber(server::asio::io_context& io, int port, const std::vector<unsigned char>& hello) {
  namespace asio = server::asio;
  server::tcp::socket socket(io);
  socket.open(server::tcp::v4());
  socket.set_option(asio::socket_base::receive_buffer_size(1024));
  socket.connect(server::tcp::endpoint(asio::ip::make_address("127.0.0.1"), static_cast<unsigned short>(port)));
  asio::write(socket, asio::buffer(hello));
  return socket;
}

}  // namespace skinstream::test
