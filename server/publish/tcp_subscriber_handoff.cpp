#include "server/publish/tcp_subscriber_handoff.h"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <string>

#include "server/publish/publish_threads.h"
#include "server/publish/subscriber_admission.h"
#include "server/publish/subscriber_hub.h"
#include "server/publish/tcp_subscriber.h"

namespace skinstream::server {

namespace {

// The same connection as a socket of `io`; false (said once, socket closed) if it cannot be.
bool move_socket_to(asio::io_context& io, tcp::socket& socket, const std::string& remote) {
  boost::system::error_code ec;
  tcp::socket own(io);
  const tcp protocol = socket.local_endpoint(ec).protocol();
  const auto handle = ec ? tcp::socket::native_handle_type(-1) : socket.release(ec);
  if (!ec) {
    own.assign(protocol, handle, ec);
    if (ec) ::close(handle);
  }
  if (ec) {
    spdlog::warn("subscriber {}: cannot hand the socket to its thread: {}; closing", remote, ec.message());
    return false;
  }
  socket = std::move(own);
  return true;
}

}  // namespace

void hand_off_tcp_subscriber(tcp::socket socket, asio::io_context& accepting, PublishThreads& publish,
                             SubscriberHub& first_hub,
                             const std::shared_ptr<SubscriberAdmission>& admission) {
  boost::system::error_code ec;
  const auto endpoint = socket.remote_endpoint(ec);
  if (ec) return;  // gone before it was taken
  const std::string remote = endpoint.address().to_string() + ":" + std::to_string(endpoint.port());
  PublishThreads::Placement placed = publish.place(accepting);
  if (&placed.io != &accepting && !move_socket_to(placed.io, socket, remote)) return;
  auto subscriber = std::make_shared<TcpSubscriber>(placed.io, first_hub, std::move(socket), remote,
                                                    std::move(placed.token));
  // Refused or not, the subscriber is answered after its Hello, in the version it speaks. With
  // a token it is admitted once it gave it; until then it holds a place kept for connections
  // without it.
  const bool token = admission->token_required();
  SubscriberAdmission::Decision admitted =
      token ? admission->admit_unauthenticated(endpoint.address()) : admission->admit(endpoint.address());
  const bool ask_token = admitted.ticket && token;
  subscriber->set_admission(std::move(admitted), ask_token ? admission : nullptr, endpoint.address());
  first_hub.add(subscriber);
  asio::post(placed.io, [subscriber] { subscriber->start(); });
}

}  // namespace skinstream::server
