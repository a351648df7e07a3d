#pragma once
// A blocking subscriber connection for one thread: connects, sends Hello, then hands each
// message to the caller as it is cut from the stream: the tests' own view of the wire (the
// programs subscribe through the client library, clients/cpp/).

#include <chrono>
#include <functional>
#include <string>

#include "protocol/subscriber/subscriber_stream.h"
#include "server/asio.h"

namespace skinstream::sub {

// "HOST:PORT" -> host, port; throws std::invalid_argument.
std::pair<std::string, std::string> split_host_port(const std::string& address);

int64_t wall_clock_ns();

class SubscriberClient {
 public:
  SubscriberClient(const std::string& host, const std::string& port, uint32_t wants);  // version 1
  // Any Hello: version 2 names a subject and an encoding; decode what comes in hello.version.
  SubscriberClient(const std::string& host, const std::string& port, const subscriber::Hello& hello);
  // Reads until `on_message` returns false or the daemon closes the connection (returns false then).
  bool run(const std::function<bool(subscriber::MessageType, std::span<const unsigned char>, int64_t receive_ns)>& on_message);

 private:
  server::asio::io_context io_;
  server::tcp::socket socket_;
  subscriber::StreamDecoder decoder_;
};

}  // namespace skinstream::sub
