#include "server/replay/qtm/qtm_server.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <optional>
#include <stdexcept>

#include <spdlog/spdlog.h>

#include "protocol/printable_text.h"
#include "protocol/qtm/qtm_capture_encoder.h"
#include "protocol/qtm/qtm_command.h"
#include "protocol/qtm/qtm_packet_framer.h"
#include "protocol/qtm/qtm_packet_reader.h"
#include "protocol/qtm/qtm_packet_writer.h"
#include "server/listener.h"
#include "server/logging.h"
#include "server/replay/replay_client.h"
#include "server/replay/replay_client_list.h"
#include "server/replay/replay_timeline.h"

namespace skinstream::server {
namespace {

using Packet = ReplayClient::Packet;

Packet shared(std::vector<unsigned char> bytes) {
  return std::make_shared<const std::vector<unsigned char>>(std::move(bytes));
}
Packet shared(std::span<const unsigned char> bytes) {
  return std::make_shared<const std::vector<unsigned char>>(bytes.begin(), bytes.end());
}

bool names(const std::vector<std::string>& components, std::string_view wanted) {
  return std::any_of(components.begin(), components.end(),
                     [&](const std::string& c) { return qtm::same_word(c, wanted) || qtm::same_word(c, "All"); });
}

}  // namespace

struct QtmServer::State : std::enable_shared_from_this<QtmServer::State> {
  struct Session;

  State(asio::io_context& io_context, std::vector<ReplaySubject> subjects, QtmServerOptions opts)
      : io(io_context),
        options(std::move(opts)),
        encoder(std::move(subjects), options.rate_hz),
        udp_socket(io),
        timeline(io, encoder.rate_hz(), options.speed, static_cast<uint64_t>(encoder.frame_count()),
                 options.loop),
        sessions(io) {}

  asio::io_context& io;
  QtmServerOptions options;
  qtm::CaptureEncoder encoder;
  qtm::DataPacketWriter writer;
  std::unique_ptr<Listener> listener;
  udp::socket udp_socket;
  ReplayTimeline timeline;
  ReplayClientList<Session> sessions;
  bool running = false;
  uint64_t latest = 0;                  // stream index of the newest frame
  std::array<Packet, 3> latest_packets;  // 3D + no labels, 3D only, no labels only: made on demand
  std::function<void()> on_finished;
  QtmServer::FrameHook frame_hook;
  QtmServerStats stats;
  RateLimitedLog log;
  const ReplayClientContext client_context{"qtm server", "qtm_bad_client", options.max_queued_frames, log,
                                           stats.clients_open, stats.bad_clients, stats.frame_packets_sent,
                                           stats.frames_dropped};

  struct Session : ReplayClient {
    Session(State& owner, tcp::socket s) : ReplayClient(std::move(s), owner.client_context), state(owner) {}

    State& state;  // sessions never outlive State: State closes them in stop()
    qtm::PacketFramer framer{1u << 20};  // a client's commands are short; a megabyte is plenty
    bool reading_paused = false;  // commands wait in the framer until the replies are read
    bool streaming = false;
    bool labelled = true, unlabelled = true;
    uint64_t divisor = 1;
    std::optional<udp::endpoint> udp_destination;

    void begin() {
      send(qtm::encode_text(qtm::PacketType::Command, qtm::kWelcome));
      read();
    }

    void read() {
      const auto room = framer.prepare(4096);
      auto handler = [keep = shared_from_this(), this](const boost::system::error_code& ec, size_t n) {
        on_read(ec, n);
      };
      socket().async_read_some(asio::buffer(room.data(), room.size()), std::move(handler));
    }

    void on_read(const boost::system::error_code& ec, size_t n) {
      if (!open()) return;
      if (ec) {
        close();
        return;
      }
      framer.commit(n);
      handle_commands();
    }

    // The commands read so far, until the replies waiting reach their bound; then the rest wait
    // (in the framer, and in the client's socket) until the client reads its replies.
    void handle_commands() {
      qtm::Bytes packet;
      while (replies_waiting() < state.options.max_queued_replies) {
        const auto status = framer.next(packet);
        if (status == qtm::PacketFramer::Status::NeedMore) return read();
        std::string error;
        if (status == qtm::PacketFramer::Status::Error || !handle(packet, error)) {
          reject(status == qtm::PacketFramer::Status::Error ? framer.error() : error);
          return;
        }
        if (!open()) return;
      }
      reading_paused = true;
      ++state.stats.reads_paused;
    }

    void send(std::vector<unsigned char> bytes) { enqueue(shared(std::move(bytes)), false); }
    void refuse(const std::string& reason) {
      ++state.stats.commands_refused;
      send(qtm::encode_text(qtm::PacketType::Error, reason));
    }

    bool handle(qtm::Bytes packet, std::string& error) {
      uint32_t type = 0;
      if (!qtm::read_header(packet, type, error)) return false;
      if (type != static_cast<uint32_t>(qtm::PacketType::Command)) {
        refuse(std::string("skinstream-replay takes commands only, not ") + qtm::packet_type_name(type) + " packets");
        return true;
      }
      std::string text;
      if (!qtm::decode_text(packet, text, error)) return false;
      ++state.stats.commands;
      qtm::Command command;
      if (!qtm::parse_command(text, command, error)) {
        refuse(error);
        return true;
      }
      using Kind = qtm::Command::Kind;
      switch (command.kind) {
        case Kind::Version:
          if (command.minor < 0)
            send(qtm::encode_text(qtm::PacketType::Command, "Version is 1." + std::to_string(qtm::kSpokenMinorVersion)));
          else if (command.major == 1 && command.minor >= qtm::kMinMinorVersion && command.minor <= qtm::kMaxMinorVersion)
            send(qtm::encode_text(qtm::PacketType::Command, "Version set to 1." + std::to_string(command.minor)));
          else
            refuse("Version NOT supported");
          break;
        case Kind::QtmVersion:
          send(qtm::encode_text(qtm::PacketType::Command, "QTM Version is 0.1 (build 0) skinstream-replay"));
          break;
        case Kind::ByteOrder:
          send(qtm::encode_text(qtm::PacketType::Command, "Byte order is little endian"));
          break;
        case Kind::GetState:
          send(qtm::encode_event(state.timeline.finished() ? qtm::Event::RtFromFileStopped
                                                           : qtm::Event::RtFromFileStarted));
          break;
        case Kind::GetParameters: {
          qtm::Parameters p = state.encoder.parameters();
          if (!names(command.components, "General")) p.frequency_hz = 0.0;  // General is left out
          p.has_3d = names(command.components, "3D");
          if (!p.has_3d) p.labels.clear();
          send(qtm::encode_text(qtm::PacketType::Xml, qtm::write_parameters_xml(p, qtm::kSpokenMinorVersion)));
          break;
        }
        case Kind::GetCurrentFrame:
          if (!choose_components(command.components)) break;
          if (state.stats.frames_produced == 0)
            send(qtm::encode_no_more_data());
          else
            enqueue(state.packet(labelled, unlabelled), true);
          break;
        case Kind::StreamFrames:
          start_streaming(command);
          break;
        case Kind::StreamFramesStop:
          streaming = false;
          break;
        case Kind::Other:
          refuse("Command not supported by skinstream-replay: " + quoted_text(command.word));
          break;
      }
      return true;
    }

    bool choose_components(const std::vector<std::string>& components) {
      labelled = names(components, "3D");
      unlabelled = names(components, "3DNoLabels");
      if (labelled || unlabelled) return true;
      refuse("skinstream-replay streams the 3D and 3DNoLabels components only");
      return false;
    }

    void start_streaming(const qtm::Command& command) {
      if (!choose_components(command.components)) return;
      const double rate = state.encoder.rate_hz();
      divisor = 1;
      if (command.rate == qtm::Command::Rate::FrequencyDivisor) divisor = command.rate_value;
      if (command.rate == qtm::Command::Rate::Frequency)
        divisor = std::max<uint64_t>(1, static_cast<uint64_t>(std::llround(rate / command.rate_value)));
      udp_destination.reset();
      if (command.udp) {
        boost::system::error_code ec;
        const auto own = socket().remote_endpoint(ec).address();
        const auto address = ec || command.udp_address.empty() ? own : asio::ip::make_address(command.udp_address, ec);
        if (ec) {
          refuse("StreamFrames: bad UDP address " + quoted_text(command.udp_address));
          return;
        }
        // Only to the client's own address: the server is no one's relay toward a third party.
        if (address != own) {
          refuse("StreamFrames: UDP only to this client's own address " + own.to_string() + ", not " + quoted_text(command.udp_address));
          return;
        }
        udp_destination = udp::endpoint(address, command.udp_port);
      }
      streaming = true;
      state.timeline.start();
    }

    // Half the replies read: its commands are taken again.
    void after_write() override {
      if (reading_paused && open() && replies_waiting() <= state.options.max_queued_replies / 2) {
        reading_paused = false;
        handle_commands();
      }
    }

    void closed() override { state.sessions.forget(this); }
  };

  // The newest frame with the components asked for (encoded once per frame and combination).
  Packet packet(bool labelled, bool unlabelled) {
    const size_t slot = labelled && unlabelled ? 0 : (labelled ? 1 : 2);
    if (!latest_packets[slot]) latest_packets[slot] = shared(encoder.encode_frame(latest, writer, labelled, unlabelled));
    return latest_packets[slot];
  }

  void start() {
    // The shared Listener: out of descriptors it pauses its accepts instead of spinning.
    listener = std::make_unique<Listener>(io, options.bind_address, options.port, "qtm server",
                                          [self = weak_from_this()](tcp::socket socket) {
                                            if (const auto state = self.lock()) state->accepted(std::move(socket));
                                          });
    running = true;
    timeline.set_on_frame([this](uint64_t k) { produce(k); });
    timeline.set_on_finished([this] { finish(); });
    listener->start();
    if (!options.start_on_first_request) timeline.start();
  }

  void accepted(tcp::socket socket) {
    if (!running) return;
    if (!admit_replay_client(stats, options.max_clients, log, "qtm")) return;  // the socket closes as it goes
    auto session = std::make_shared<Session>(*this, std::move(socket));
    sessions.add(session);
    session->begin();
  }

  void stop() {
    if (!running) return;
    running = false;
    boost::system::error_code ignored;
    if (listener) {
      listener->stop();
      asio::post(io, [done = std::move(listener)] {});  // after its cancelled accept's handler
    }
    udp_socket.close(ignored);
    timeline.stop();
    sessions.close_all();
  }

  void produce(uint64_t k) {
    latest = k;
    latest_packets = {};
    ++stats.frames_produced;
    if (frame_hook)
      frame_hook(encoder.frame_number(k),
                 std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch()).count());
    const bool capture = options.capture_end > options.capture_first;
    for (auto& session : sessions.snapshot()) {
      if (capture && session->open() && session->streaming &&
          (k == options.capture_first || k == options.capture_end))
        session->send(qtm::encode_event(k == options.capture_first ? qtm::Event::CaptureStarted
                                                                   : qtm::Event::CaptureStopped));
      if (!session->open() || !session->streaming || k % session->divisor != 0) continue;
      Packet p = packet(session->labelled, session->unlabelled);
      if (session->udp_destination)
        send_datagram(std::move(p), *session->udp_destination);
      else
        session->enqueue(std::move(p), true);
    }
  }

  void send_datagram(Packet packet, const udp::endpoint& destination) {
    boost::system::error_code ec;
    if (!udp_socket.is_open()) udp_socket.open(destination.protocol(), ec);
    if (ec) return;
    udp_socket.async_send_to(asio::buffer(*packet), destination,
                             [self = shared_from_this(), packet](const boost::system::error_code& e, size_t) {
                               if (!e) ++self->stats.datagrams_sent;
                             });
  }

  void finish() {
    for (auto& session : sessions.snapshot()) {
      if (!session->open() || !session->streaming) continue;
      session->send(qtm::encode_event(qtm::Event::RtFromFileStopped));
      session->send(qtm::encode_no_more_data());
      session->streaming = false;
    }
    if (on_finished) on_finished();
  }
};

QtmServer::QtmServer(asio::io_context& io, std::vector<ReplaySubject> subjects, QtmServerOptions options)
    : state_(std::make_shared<State>(io, std::move(subjects), std::move(options))) {}

QtmServer::~QtmServer() { stop(); }

void QtmServer::start() { state_->start(); }
void QtmServer::stop() { state_->stop(); }
uint16_t QtmServer::port() const { return state_->listener ? static_cast<uint16_t>(state_->listener->port()) : 0; }
void QtmServer::set_on_finished(std::function<void()> on_finished) { state_->on_finished = std::move(on_finished); }
void QtmServer::set_frame_hook(FrameHook hook) { state_->frame_hook = std::move(hook); }
bool QtmServer::finished() const { return state_->timeline.finished(); }
bool QtmServer::all_clients_idle() const { return state_->sessions.all_idle(); }
const QtmServerStats& QtmServer::stats() const { return state_->stats; }

}  // namespace skinstream::server
