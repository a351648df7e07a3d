#include "server/replay/vicon/vicon_server.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <vector>

#include <spdlog/spdlog.h>

#include "protocol/vicon/vicon_capture_encoder.h"
#include "protocol/vicon/vicon_packet_framer.h"
#include "protocol/vicon/vicon_packet_reader.h"
#include "protocol/vicon/vicon_packet_writer.h"
#include "server/listener.h"
#include "server/logging.h"
#include "server/replay/replay_client.h"
#include "server/replay/replay_client_list.h"
#include "server/replay/replay_timeline.h"
#include "server/system_clock.h"

namespace skinstream::server {
namespace {

using Packet = ReplayClient::Packet;

Packet copy_packet(std::span<const unsigned char> bytes) {
  return std::make_shared<const std::vector<unsigned char>>(bytes.begin(), bytes.end());
}

bool contains(const std::vector<uint32_t>& set, uint32_t type) {
  return std::find(set.begin(), set.end(), type) != set.end();
}

// The packet with only the objects of the wanted types (the client's ObjectEnums answer).
Packet filter_packet(const Packet& packet, const std::vector<uint32_t>& wanted) {
  std::vector<vicon::ObjectView> objects;
  std::string error;
  if (!vicon::split_objects(*packet, objects, error)) return packet;  // our own packets are well formed
  if (std::all_of(objects.begin(), objects.end(), [&](const auto& o) { return contains(wanted, o.type); }))
    return packet;
  vicon::PacketWriter writer;
  for (const auto& o : objects)
    if (contains(wanted, o.type)) writer.add_raw(o.type, o.payload);
  return copy_packet(writer.finish());
}

}  // namespace

struct ViconServer::State : std::enable_shared_from_this<ViconServer::State> {
  struct Session;

  State(asio::io_context& io_context, std::vector<ReplaySubject> subjects, ViconServerOptions opts)
      : io(io_context),
        options(std::move(opts)),
        encoder(subjects, options.rate_hz, options.loop),
        timeline(io, encoder.rate_hz(), options.speed, static_cast<uint64_t>(encoder.frame_count()),
                 options.loop),
        multicast_socket(io),
        sessions(io) {}

  asio::io_context& io;
  ViconServerOptions options;
  vicon::CaptureFrameEncoder encoder;
  vicon::PacketWriter writer;
  std::unique_ptr<Listener> listener;  // from start() until stop()
  RateLimitedLog log;                  // refusals and malformed clients, which come in floods
  ReplayTimeline timeline;
  udp::socket multicast_socket;
  struct MulticastDestination {
    udp::endpoint endpoint;
    const void* client = nullptr;  // the session that asked (null: the operator, start_multicast)
  };
  std::vector<MulticastDestination> multicast_destinations;
  ReplayClientList<Session> sessions;
  Packet object_enums_packet;

  bool running = false;
  uint64_t latest_sequence = 0;    // k of the newest produced frame (valid when produced > 0)
  uint32_t latest_frame_number = 0;
  uint64_t latest_listed = 0;      // the subjects the newest frame lists (CaptureFrameEncoder::listed)
  Packet latest_plain;             // the newest frame without static objects
  Packet latest_with_static;       // ... and with them (made when a client first needs it)

  FrameHook frame_hook;
  std::function<void()> on_finished;
  ViconServerStats stats;
  const ReplayClientContext client_context{"vicon server", "vicon_bad_client", options.max_queued_frames, log,
                                           stats.clients_open, stats.bad_clients, stats.frame_packets_sent,
                                           stats.frames_dropped};

  // ---- one TCP client ----
  struct Session : ReplayClient {
    Session(State& owner, tcp::socket s) : ReplayClient(std::move(s), owner.client_context), state(owner) {}

    State& state;  // sessions never outlive State: State closes them in stop()
    vicon::PacketFramer framer{kMaxClientPacketBytes};
    bool push = false;
    int pull_requests = 0;
    bool sent_any_frame = false;
    uint64_t listed_sent = 0;  // the subjects listed in the SubjectInfo it was sent last
    bool has_last_sent = false;
    uint64_t last_sent_sequence = 0;
    std::vector<uint32_t> wanted;  // empty: everything offered

    void begin() {
      enqueue(state.object_enums_packet, false);
      read();
    }

    void read() {
      const auto room = framer.prepare(16 * 1024);
      auto handler = [keep = shared_from_this(), this](const boost::system::error_code& ec, size_t n) {
        on_read(ec, n);
      };
      socket().async_read_some(asio::buffer(room.data(), room.size()), std::move(handler));
    }

    void on_read(const boost::system::error_code& ec, size_t n) {
      if (!open()) return;
      if (ec) {
        if (ec != asio::error::eof && ec != asio::error::operation_aborted)
          spdlog::debug("vicon server: client read: {}", ec.message());
        close();
        return;
      }
      framer.commit(n);
      vicon::Bytes packet;
      for (;;) {
        const auto status = framer.next(packet);
        if (status == vicon::PacketFramer::Status::NeedMore) break;
        std::string error;
        if (status == vicon::PacketFramer::Status::Error || !handle(framer.objects(), error)) {
          reject(status == vicon::PacketFramer::Status::Error ? framer.error() : error);
          return;
        }
      }
      read();
    }

    bool handle(const std::vector<vicon::ObjectView>& objects, std::string& error) {
      namespace type = vicon::object_type;
      for (const vicon::ObjectView& object : objects) {
        switch (object.type) {
          case type::ObjectEnums: {
            vicon::ObjectEnums asked;
            if (!vicon::decode(object.payload, asked, error)) return false;
            wanted = asked.types;
            break;
          }
          case type::RequestFrame: {
            vicon::RequestFrame request;
            if (!vicon::decode(object.payload, request, error)) return false;
            push = request.streaming;
            if (!push) ++pull_requests;
            state.client_wants_frames(*this);
            break;
          }
          case type::RequestNextFrame: {
            vicon::RequestNextFrame request;
            if (!vicon::decode(object.payload, request, error)) return false;
            ++pull_requests;
            state.client_wants_frames(*this);
            break;
          }
          case type::Ping: {
            vicon::Ping ping;
            if (!vicon::decode(object.payload, ping, error)) return false;
            enqueue(copy_packet(vicon::encode_packet(ping)), false);
            break;
          }
          case type::StartMulticastSender: {
            vicon::StartMulticastSender request;
            if (!vicon::decode(object.payload, request, error)) return false;
            state.add_multicast(udp::endpoint(asio::ip::address_v4(request.multicast_address), request.port), this);
            break;
          }
          case type::StopMulticastSender:
            state.remove_multicast(this);
            break;
          case type::Filter: {  // accepted; a single-subject stream has nothing to filter
            vicon::Filter filter;
            if (!vicon::decode(object.payload, filter, error)) return false;
            break;
          }
          default:  // Contents, KeepAlive, haptics and types of newer SDKs: nothing to do
            break;
        }
      }
      return true;
    }

    void closed() override {
      state.remove_multicast(this);  // nothing is sent for it once it left
      state.sessions.forget(this);
    }
  };

  void start() {
    // The daemon's listener: out of descriptors it pauses its accepts instead of retrying at once.
    listener = std::make_unique<Listener>(
        io, options.bind_address, options.port, "vicon server",
        [weak = weak_from_this()](tcp::socket socket) {
          if (const auto self = weak.lock()) self->on_accept(std::move(socket));
        },
        ListenerOptions{options.tcp_congestion});
    object_enums_packet = copy_packet(vicon::encode_packet(vicon::CaptureFrameEncoder::offered_types()));
    running = true;
    timeline.set_on_frame([this](uint64_t k) { produce(k); });
    timeline.set_on_finished([this] {
      if (on_finished) on_finished();
    });
    listener->start();
    if (!options.start_on_first_request) start_timeline();
  }

  void on_accept(tcp::socket socket) {
    if (!running) return;
    if (!admit_replay_client(stats, options.max_clients, log, "vicon"))
      return;  // the socket closes as it goes
    boost::system::error_code ignored;
    if (options.socket_send_buffer_bytes > 0)
      socket.set_option(asio::socket_base::send_buffer_size(options.socket_send_buffer_bytes), ignored);
    auto session = std::make_shared<Session>(*this, std::move(socket));
    sessions.add(session);
    session->begin();
  }

  void stop() {
    if (!running) return;
    running = false;
    boost::system::error_code ignored;
    listener->stop();
    // Its cancelled handlers are queued and use it: freed after them.
    asio::post(io, [done = std::move(listener)] {});
    timeline.stop();
    multicast_socket.close(ignored);
    sessions.close_all();
  }

  void client_wants_frames(Session& session) {
    if (!timeline.started()) {
      start_timeline();
      return;  // the first frame goes out at once from the timer
    }
    serve(session);
  }

  // Only while serving: a multicast destination named before start() waits for it.
  void start_timeline() {
    if (running) timeline.start();
  }

  void produce(uint64_t sequence) {
    const auto frame_number = static_cast<uint32_t>(static_cast<int64_t>(encoder.first_frame()) + static_cast<int64_t>(sequence));
    encoder.encode_frame(sequence, frame_number, false, writer);
    latest_plain = copy_packet(writer.finish());
    latest_with_static.reset();
    latest_sequence = sequence;
    latest_listed = encoder.listed(sequence);
    latest_frame_number = frame_number;
    ++stats.frames_produced;

    // The send time is taken, and handed on, before the first client is served: Asio writes
    // speculatively, so a client on loopback can have the frame before serve() returns, and a
    // hook called afterwards could be late (seen by skinstream-bench as frames without a send
    // time, 3 in 288,000).
    if (frame_hook) frame_hook(frame_number, system_now_ns());
    for (auto& session : sessions.snapshot()) serve(*session);
    send_multicast();
  }

  const Packet& with_static() {
    if (!latest_with_static) {
      encoder.encode_frame(latest_sequence, latest_frame_number, true, writer);
      latest_with_static = copy_packet(writer.finish());
    }
    return latest_with_static;
  }

  // Sends the newest frame to a client that wants it and has not had it.
  void serve(Session& session) {
    if (!session.open() || stats.frames_produced == 0) return;
    if (!session.push && session.pull_requests <= 0) return;
    if (session.has_last_sent && session.last_sent_sequence >= latest_sequence) return;
    // Static objects in a client's first frame and whenever the subjects listed changed.
    const bool needs_static = !session.sent_any_frame || session.listed_sent != latest_listed;
    Packet packet = needs_static ? with_static() : latest_plain;
    if (!session.wanted.empty()) packet = filter_packet(packet, session.wanted);
    session.sent_any_frame = true;
    session.listed_sent = latest_listed;
    session.has_last_sent = true;
    session.last_sent_sequence = latest_sequence;
    if (!session.push) --session.pull_requests;
    session.enqueue(std::move(packet), true);
  }

  // `client`: the session that asked (null: the operator). A client may name a multicast group
  // or its own address, nothing else: the server is no one's relay toward a third party.
  void add_multicast(const udp::endpoint& destination, const Session* client = nullptr) {
    boost::system::error_code ec;
    if (client) {
      const auto own = client->socket().remote_endpoint(ec).address();
      const bool own_address = !ec && destination.address() == (own.is_v6() && own.to_v6().is_v4_mapped()
                                                                    ? asio::ip::address(asio::ip::make_address_v4(asio::ip::v4_mapped, own.to_v6()))
                                                                    : own);
      const bool full = multicast_destinations.size() >= options.max_multicast_destinations;
      if ((!destination.address().is_multicast() && !own_address) || full) {
        ++stats.multicast_requests_refused;
        log.warn("vicon_multicast_refused", "vicon server: not sending to " + destination.address().to_string() + ":" +
                                                std::to_string(destination.port()) +
                                                (full ? ": already sending to as many as allowed" : ": neither a multicast group nor the asking client's address"));
        return;
      }
      ec.clear();
    }
    if (!multicast_socket.is_open()) {
      multicast_socket.open(udp::v4(), ec);
      if (!ec) multicast_socket.set_option(asio::ip::multicast::hops(options.multicast_ttl), ec);
      if (!ec) multicast_socket.set_option(asio::ip::multicast::enable_loopback(true), ec);
      if (ec) {
        spdlog::warn("vicon server: cannot open the multicast socket: {}", ec.message());
        return;
      }
    }
    if (std::none_of(multicast_destinations.begin(), multicast_destinations.end(),
                     [&](const MulticastDestination& d) { return d.endpoint == destination && d.client == client; }))
      multicast_destinations.push_back({destination, client});
    spdlog::info("vicon server: multicasting to {}:{}", destination.address().to_string(), destination.port());
    start_timeline();
  }

  // What `client` asked for (StopMulticastSender, or it left).
  void remove_multicast(const Session* client) {
    std::erase_if(multicast_destinations, [client](const MulticastDestination& d) { return d.client == client; });
  }

  void send_multicast() {
    if (multicast_destinations.empty() || !multicast_socket.is_open()) return;
    const Packet packet = with_static();  // datagrams are independent: each carries everything
    if (packet->size() > 65507) {
      ++stats.datagrams_too_large;
      return;
    }
    for (const MulticastDestination& destination : multicast_destinations) {
      multicast_socket.async_send_to(asio::buffer(*packet), destination.endpoint,
                                     [self = shared_from_this(), packet](const boost::system::error_code& ec, size_t) {
                                       if (!ec) ++self->stats.datagrams_sent;
                                     });
    }
  }
};

ViconServer::ViconServer(asio::io_context& io, std::vector<ReplaySubject> subjects, ViconServerOptions options)
    : state_(std::make_shared<State>(io, std::move(subjects), std::move(options))) {}

ViconServer::ViconServer(asio::io_context& io, const Capture& capture, ViconServerOptions options)
    : ViconServer(io, {{options.subject_name, &capture}}, options) {}

ViconServer::~ViconServer() { stop(); }

void ViconServer::start() { state_->start(); }
void ViconServer::stop() { state_->stop(); }
uint16_t ViconServer::port() const {
  return state_->listener ? static_cast<uint16_t>(state_->listener->port()) : 0;
}
void ViconServer::set_frame_hook(FrameHook hook) { state_->frame_hook = std::move(hook); }
void ViconServer::set_on_finished(std::function<void()> on_finished) { state_->on_finished = std::move(on_finished); }
void ViconServer::start_multicast(const std::string& address, uint16_t port) {
  state_->add_multicast(udp::endpoint(asio::ip::make_address(address), port));
}
bool ViconServer::finished() const { return state_->timeline.finished(); }
bool ViconServer::all_clients_idle() const { return state_->sessions.all_idle(); }
const ViconServerStats& ViconServer::stats() const { return state_->stats; }

}  // namespace skinstream::server
