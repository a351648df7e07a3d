#include "server/replay/natnet/natnet_server.h"

#include <algorithm>
#include <deque>
#include <stdexcept>

#include <spdlog/spdlog.h>

#include "protocol/natnet/natnet_capture_encoder.h"
#include "protocol/natnet/natnet_reader.h"
#include "protocol/natnet/natnet_writer.h"
#include "server/logging.h"
#include "server/replay/replay_timeline.h"

namespace skinstream::server {
namespace {

using Packet = std::shared_ptr<const std::vector<unsigned char>>;
using Clock = std::chrono::steady_clock;

}  // namespace

struct NatNetServer::State : std::enable_shared_from_this<NatNetServer::State> {
  State(asio::io_context& io_context, std::vector<ReplaySubject> subjects, NatNetServerOptions opts)
      : io(io_context),
        options(std::move(opts)),
        encoder(std::move(subjects), options.rate_hz),
        command_socket(io),
        timeline(io, encoder.rate_hz(), options.speed, static_cast<uint64_t>(encoder.frame_count()), options.loop) {
    receive_buffer.resize(natnet::kMaxMessageBytes);
    encoder.set_clock({options.timestamp_jitter_us * 1e-6, options.timestamp_clock_hz, 1,
                       options.capture_latency_us * 1e-6});
    encoder.set_recording_frames(options.recording_first, options.recording_end);
  }

  struct Client {
    udp::endpoint endpoint;
    Clock::time_point last_heard;
  };

  asio::io_context& io;
  NatNetServerOptions options;
  natnet::CaptureEncoder encoder;
  udp::socket command_socket;  // commands in, answers and unicast frames out
  ReplayTimeline timeline;
  std::vector<unsigned char> receive_buffer;
  udp::endpoint sender;
  udp::endpoint multicast_destination;
  std::vector<Client> clients;  // unicast: frames go to them
  std::deque<udp::endpoint> connected;  // the last senders of a CONNECT, newest last
  natnet::ByteVector frame_bytes;
  Packet latest;
  bool running = false;
  std::function<void()> on_finished;
  NatNetServer::FrameHook frame_hook;
  NatNetServerStats stats;
  RateLimitedLog log;

  void start() {
    const udp::endpoint endpoint(asio::ip::make_address(options.bind_address), options.command_port);
    boost::system::error_code ec;
    command_socket.open(endpoint.protocol(), ec);
    if (!ec) command_socket.set_option(udp::socket::reuse_address(true), ec);
    if (!ec) command_socket.bind(endpoint, ec);
    if (!ec && options.multicast) {
      multicast_destination = udp::endpoint(asio::ip::make_address(options.multicast_group, ec), options.data_port);
      if (!ec) command_socket.set_option(asio::ip::multicast::hops(options.multicast_ttl), ec);
      if (!ec) command_socket.set_option(asio::ip::multicast::enable_loopback(true), ec);
      if (!ec && !options.multicast_interface.empty())
        command_socket.set_option(
            asio::ip::multicast::outbound_interface(asio::ip::make_address_v4(options.multicast_interface)), ec);
    }
    if (ec)
      throw std::runtime_error("cannot serve NatNet on " + options.bind_address + ":" +
                               std::to_string(options.command_port) + ": " + ec.message());
    running = true;
    timeline.set_on_frame([this](uint64_t k) { produce(k); });
    timeline.set_on_finished([this] {
      if (on_finished) on_finished();
    });
    receive();
    if (!options.start_on_first_request) timeline.start();
  }

  void stop() {
    if (!running) return;
    running = false;
    timeline.stop();
    boost::system::error_code ignored;
    command_socket.close(ignored);
  }

  void receive() {
    command_socket.async_receive_from(
        asio::buffer(receive_buffer), sender,
        [self = shared_from_this()](const boost::system::error_code& ec, size_t n) {
          if (!self->running || ec == asio::error::operation_aborted) return;
          if (!ec) self->handle(natnet::Bytes(self->receive_buffer.data(), n), self->sender);
          self->receive();
        });
  }

  void reply(natnet::ByteVector bytes, const udp::endpoint& to) {
    auto packet = std::make_shared<const natnet::ByteVector>(std::move(bytes));
    send(packet, to);
  }

  void send(const Packet& packet, const udp::endpoint& to) {
    command_socket.async_send_to(asio::buffer(*packet), to,
                                 [self = shared_from_this(), packet](const boost::system::error_code& ec, size_t) {
                                   if (!ec) ++self->stats.datagrams_sent;
                                 });
  }

  void handle(natnet::Bytes datagram, const udp::endpoint& from) {
    uint16_t id = 0;
    natnet::Bytes payload;
    std::string error;
    if (!natnet::read_message(datagram, id, payload, error)) {
      ++stats.bad_datagrams;
      log.warn("natnet_bad_datagram", "natnet server: ignoring a malformed datagram from " +
                                          from.address().to_string() + ": " + error);
      return;
    }
    ++stats.requests;
    switch (id) {
      case natnet::message::Connect: {
        if (!options.multicast && !is_client(from) && clients.size() >= options.max_clients) {
          ++stats.clients_refused;
          log.warn("natnet_too_many_clients", "natnet server: not answering a CONNECT from " + from.address().to_string() +
                                                  ": " + std::to_string(options.max_clients) + " unicast clients already");
          break;
        }
        note_connected(from);
        natnet::ServerInfo info;
        info.application_name = "skinstream-replay";
        info.application_version = {0, 1, 0, 0};
        info.natnet_version = {static_cast<uint8_t>(options.version.major), static_cast<uint8_t>(options.version.minor), 0,
                               0};
        info.data_port = options.data_port;
        info.multicast = options.multicast;
        if (options.multicast) info.multicast_group = multicast_destination.address().to_v4().to_bytes();
        reply(natnet::encode_server_info(info), from);
        if (!options.multicast) remember(from);
        timeline.start();
        break;
      }
      case natnet::message::RequestModelDef:
        if (!was_connected(from)) break;
        reply(natnet::encode_model_definitions(encoder.model_definitions(), options.version), from);
        break;
      case natnet::message::RequestFrameOfData:
        if (!was_connected(from)) break;
        if (latest) send(latest, from);
        break;
      case natnet::message::KeepAlive:
        if (!options.multicast && is_client(from)) remember(from);  // keeps a client; makes none
        break;
      case natnet::message::Disconnect:
        clients.erase(std::remove_if(clients.begin(), clients.end(), [&](const Client& c) { return c.endpoint == from; }),
                      clients.end());
        break;
      case natnet::message::Request:  // text commands (TimelinePlay, Bitstream, ...): a replay takes none
        reply(natnet::encode_empty(natnet::message::UnrecognizedRequest), from);
        break;
      default:  // answers and frames from another server: never answered, so two servers cannot ping-pong
        break;
    }
  }

  bool is_client(const udp::endpoint& from) const {
    return std::any_of(clients.begin(), clients.end(), [&](const Client& c) { return c.endpoint == from; });
  }

  void note_connected(const udp::endpoint& from) {
    connected.erase(std::remove(connected.begin(), connected.end(), from), connected.end());
    connected.push_back(from);
    while (connected.size() > std::max<size_t>(1, options.max_clients)) connected.pop_front();
  }

  bool was_connected(const udp::endpoint& from) {
    if (std::find(connected.begin(), connected.end(), from) != connected.end()) return true;
    ++stats.requests_not_connected;
    log.warn("natnet_not_connected", "natnet server: not answering a request from " + from.address().to_string() + ":" +
                                         std::to_string(from.port()) + ", which did not CONNECT");
    return false;
  }

  void remember(const udp::endpoint& from) {
    const auto it = std::find_if(clients.begin(), clients.end(), [&](const Client& c) { return c.endpoint == from; });
    if (it != clients.end()) {
      it->last_heard = Clock::now();
      return;
    }
    clients.push_back({from, Clock::now()});
    ++stats.clients_connected;
  }

  void produce(uint64_t k) {
    ++stats.frames_produced;
    try {
      encoder.encode(k, options.version, frame_bytes);
    } catch (const std::length_error& e) {
      ++stats.frames_too_large;
      log.warn("natnet_frame_too_large", std::string("natnet server: frame not sent: ") + e.what());
      return;
    }
    if (frame_bytes.size() > natnet::kMaxDatagramBytes) {
      ++stats.frames_too_large;
      return;
    }
    latest = std::make_shared<const natnet::ByteVector>(frame_bytes);
    if (frame_hook)
      frame_hook(encoder.frame_number(k),
                 std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch()).count());
    if (options.multicast) {
      send(latest, multicast_destination);
      return;
    }
    const auto now = Clock::now();
    const auto before = clients.size();
    clients.erase(std::remove_if(clients.begin(), clients.end(),
                                 [&](const Client& c) { return now - c.last_heard > options.client_timeout; }),
                  clients.end());
    stats.clients_timed_out += before - clients.size();
    for (const Client& c : clients) send(latest, c.endpoint);
  }
};

NatNetServer::NatNetServer(asio::io_context& io, std::vector<ReplaySubject> subjects, NatNetServerOptions options)
    : state_(std::make_shared<State>(io, std::move(subjects), std::move(options))) {}
NatNetServer::~NatNetServer() { stop(); }
void NatNetServer::start() { state_->start(); }
void NatNetServer::stop() { state_->stop(); }
uint16_t NatNetServer::command_port() const {
  boost::system::error_code ec;
  const auto endpoint = state_->command_socket.local_endpoint(ec);
  return ec ? 0 : endpoint.port();
}
void NatNetServer::set_on_finished(std::function<void()> on_finished) { state_->on_finished = std::move(on_finished); }
void NatNetServer::set_frame_hook(FrameHook hook) { state_->frame_hook = std::move(hook); }
bool NatNetServer::finished() const { return state_->timeline.finished(); }
const NatNetServerStats& NatNetServer::stats() const { return state_->stats; }

}  // namespace skinstream::server
