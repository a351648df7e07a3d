#include "server/ingest/natnet_source.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <unordered_map>

#include "protocol/natnet/natnet_reader.h"
#include "protocol/natnet/natnet_writer.h"
#include "server/ingest/source_lifecycle.h"
#include "server/ingest/source_rate_estimate.h"
#include "server/ingest/source_reconnection.h"
#include "server/system_clock.h"

namespace skinstream::server {
namespace {

using Clock = std::chrono::steady_clock;

Vec3 millimetres(const natnet::Point& metres) {
  return Vec3(1000.0 * metres[0], 1000.0 * metres[1], 1000.0 * metres[2]);
}

constexpr auto kWatchdogPeriod = std::chrono::milliseconds(100);
constexpr natnet::Version kWanted{4, 1};

}  // namespace

struct NatNetSource::State : std::enable_shared_from_this<NatNetSource::State> {
  enum class Phase { ServerInfo, ModelDef, Streaming };

  State(asio::io_context& io_context, NatNetSourceOptions opts, SourceSink& source_sink)
      : io(io_context),
        options(std::move(opts)),
        sink(source_sink),
        command_socket(io),
        data_socket(io),
        resolver(io),
        watchdog(io),
        keep_alive_timer(io),
        reconnection(io, sink, options.initial_backoff_seconds, options.max_backoff_seconds) {
    command_buffer.resize(natnet::kMaxMessageBytes);
    data_buffer.resize(natnet::kMaxMessageBytes);
  }

  asio::io_context& io;
  NatNetSourceOptions options;
  SourceSink& sink;
  udp::socket command_socket;  // requests out; answers, and unicast frames, in
  udp::socket data_socket;     // multicast frames
  udp::resolver resolver;
  asio::steady_timer watchdog, keep_alive_timer;
  SourceReconnection reconnection;
  udp::endpoint server;
  udp::endpoint command_sender, data_sender;
  std::vector<unsigned char> command_buffer, data_buffer;
  natnet::Version version;
  natnet::ServerInfo server_info;
  natnet::ModelDefinitions definitions;
  natnet::FrameOfData data;
  SourceFrame frame;
  std::unordered_map<std::string, size_t> subject_of;  // marker set name -> subject index
  Phase phase = Phase::ServerInfo;
  Clock::time_point phase_start, last_frame, last_model_request;
  SourceRateEstimate rate;  // NatNet sends no rate: from the frames' numbers and timestamps
  uint64_t generation = 0;
  std::atomic<bool> stopped{false};

  std::string where() const { return options.host + ":" + std::to_string(options.command_port); }

  void connect() {
    if (stopped) return;
    const uint64_t gen = ++generation;
    phase = Phase::ServerInfo;
    phase_start = Clock::now();
    rate.reset();
    resolver.async_resolve(udp::v4(), options.host, std::to_string(options.command_port),
                           [self = shared_from_this(), gen](const boost::system::error_code& ec,
                                                            const udp::resolver::results_type& results) {
                             if (self->stopped || gen != self->generation) return;
                             if (ec || results.empty())
                               return self->fail(gen, "cannot resolve " + self->where() + ": " + ec.message());
                             self->server = results.begin()->endpoint();
                             self->open_command_socket(gen);
                           });
  }

  // The address to bind the command socket to: the one configured (an IPv4 address), or this
  // host's address on the route to the server (what a connected socket is given).
  asio::ip::address_v4 local_address(boost::system::error_code& ec) {
    const auto configured = asio::ip::make_address_v4(options.bind_address, ec);
    if (!ec && !configured.is_unspecified()) return configured;
    ec.clear();
    udp::socket probe(io);
    probe.open(udp::v4(), ec);
    if (!ec) probe.connect(server, ec);  // no datagram is sent: the kernel only picks the route
    const udp::endpoint local = ec ? udp::endpoint() : probe.local_endpoint(ec);
    return ec ? asio::ip::address_v4() : local.address().to_v4();
  }

  void open_command_socket(uint64_t gen) {
    boost::system::error_code ec;
    const auto local = local_address(ec);
    if (ec) return fail(gen, "no local address toward " + where() + " (bind " + options.bind_address + "): " + ec.message());
    command_socket.open(udp::v4(), ec);
    if (!ec) command_socket.bind(udp::endpoint(local, 0), ec);
    if (ec) return fail(gen, "cannot open a UDP socket on " + local.to_string() + ": " + ec.message());
    receive(gen, command_socket, command_buffer, command_sender);
    send(natnet::encode_connect("skinstream", kWanted));
    watch(gen);
  }

  void open_data_socket(uint64_t gen) {
    boost::system::error_code ec;
    const auto group = asio::ip::address_v4(server_info.multicast_group);
    const auto interface = asio::ip::make_address_v4(options.interface_address, ec);
    if (!ec) data_socket.open(udp::v4(), ec);
    if (!ec) data_socket.set_option(udp::socket::reuse_address(true), ec);
    if (!ec) data_socket.bind(udp::endpoint(udp::v4(), server_info.data_port), ec);
    if (!ec) data_socket.set_option(asio::ip::multicast::join_group(group, interface), ec);
    if (ec)
      return fail(gen, "cannot join multicast group " + group.to_string() + ":" +
                           std::to_string(server_info.data_port) + " on " + options.interface_address + ": " +
                           ec.message());
    receive(gen, data_socket, data_buffer, data_sender);
  }

  void receive(uint64_t gen, udp::socket& socket, std::vector<unsigned char>& buffer, udp::endpoint& sender) {
    socket.async_receive_from(asio::buffer(buffer), sender,
                              [self = shared_from_this(), gen, &socket, &buffer, &sender](
                                  const boost::system::error_code& ec, size_t n) {
                                if (self->stopped || gen != self->generation) return;
                                if (!ec && &socket == &self->command_socket && sender.address() != self->server.address())
                                  self->sink.on_bad_input("foreign_datagram", "NatNet: dropped a datagram from " +
                                                                                  sender.address().to_string() + ", not the server " +
                                                                                  self->server.address().to_string());
                                else if (!ec)
                                  self->on_datagram(gen, natnet::Bytes(buffer.data(), n));
                                if (self->stopped || gen != self->generation) return;
                                if (ec && ec != asio::error::message_size && ec != asio::error::connection_refused)
                                  return self->fail(gen, "cannot receive from " + self->where() + ": " + ec.message());
                                self->receive(gen, socket, buffer, sender);
                              });
  }

  void send(natnet::ByteVector bytes) {
    auto buffer = std::make_shared<natnet::ByteVector>(std::move(bytes));
    command_socket.async_send_to(asio::buffer(*buffer), server, [buffer](const boost::system::error_code&, size_t) {});
  }

  void request_model_definitions() {
    last_model_request = Clock::now();
    send(natnet::encode_empty(natnet::message::RequestModelDef));
  }

  void on_datagram(uint64_t gen, natnet::Bytes datagram) {
    uint16_t id = 0;
    natnet::Bytes payload;
    std::string error;
    if (!natnet::read_message(datagram, id, payload, error)) {
      sink.on_bad_input("malformed_packet", "NatNet: " + error);
      return;
    }
    switch (id) {
      case natnet::message::ServerInfo:
        if (phase != Phase::ServerInfo) return;
        if (!natnet::decode_server_info(payload, server_info, error)) {
          sink.on_bad_input("malformed_packet", "NatNet server info: " + error);
          return;
        }
        version = server_info.version();
        if (!version.supported())
          return fail(gen, "the server speaks NatNet " + std::to_string(version.major) + "." +
                               std::to_string(version.minor) + "; 3.0 or later is needed");
        if (server_info.multicast) open_data_socket(gen);
        if (stopped || gen != generation) return;
        if (!server_info.multicast) keep_alive(gen);
        phase = Phase::ModelDef;
        phase_start = Clock::now();
        request_model_definitions();
        return;
      case natnet::message::ModelDef:
        if (phase == Phase::ServerInfo) return;
        if (!natnet::decode_model_definitions(payload, version, definitions, error)) {
          sink.on_bad_input("malformed_packet", "NatNet model definitions: " + error);
          return;
        }
        set_subjects();
        if (phase == Phase::ModelDef) {
          phase = Phase::Streaming;
          phase_start = last_frame = Clock::now();
        }
        return;
      case natnet::message::FrameOfData:
        if (phase != Phase::Streaming) return;  // not readable before the definitions
        if (!natnet::decode_frame(payload, version, data, error)) {
          sink.on_bad_input("malformed_packet", "NatNet frame: " + error);
          return;
        }
        last_frame = Clock::now();
        on_frame();
        return;
      default:
        return;  // responses, message strings, unrecognised-request answers: nothing to act on
    }
  }

  void set_subjects() {
    std::vector<SourceSubject> subjects;
    subject_of.clear();
    for (const natnet::MarkerSetDescription& set : definitions.marker_sets) {
      if (set.name == "all" || subject_of.count(set.name)) continue;
      subject_of.emplace(set.name, subjects.size());
      subjects.push_back({set.name, set.markers});
    }
    const bool changed = subjects.size() != frame.subjects.size() ||
                         !std::equal(subjects.begin(), subjects.end(), frame.subjects.begin(),
                                     [](const SourceSubject& a, const SourceSubject& b) {
                                       return a.name == b.name && a.labels == b.labels;
                                     });
    if (!changed) return;
    frame.subjects = std::move(subjects);
    frame.labelled.resize(frame.subjects.size());
    for (size_t s = 0; s < frame.subjects.size(); ++s)
      frame.labelled[s].assign(frame.subjects[s].labels.size(), missing_point());
    ++frame.structure_version;
  }

  void on_frame() {
    bool unknown_set = false;
    for (auto& subject : frame.labelled)
      for (Vec3& p : subject) p = missing_point();
    for (size_t i = 0; i < data.marker_set_count; ++i) {
      const natnet::MarkerSetData& set = data.marker_sets[i];
      const auto it = subject_of.find(set.name);
      if (it == subject_of.end() || set.positions.size() != frame.labelled[it->second].size()) {
        unknown_set = unknown_set || set.name != "all";
        continue;
      }
      std::vector<Vec3>& out = frame.labelled[it->second];
      for (size_t m = 0; m < out.size(); ++m) {
        const Vec3 p = millimetres(set.positions[m]);
        out[m] = is_present(p) ? p : missing_point();
      }
    }
    if (unknown_set)
      sink.on_bad_input("unknown_marker_set", "NatNet frame " + std::to_string(data.frame_number) +
                                                  " has a marker set the model definitions do not describe; "
                                                  "asking for them again");
    if ((unknown_set || (data.params & natnet::kFrameTrackedModelsChanged)) &&
        Clock::now() - last_model_request >= options.model_request_interval)
      request_model_definitions();
    frame.unlabelled.clear();
    frame.unlabelled_ids.clear();
    for (const natnet::LabelledMarker& m : data.labelled_markers) {
      if (m.model_id() != 0) continue;  // a marker of a marker set: already read above
      const Vec3 p = millimetres(m.position);
      if (!is_present(p) || (m.params & natnet::kMarkerOccluded)) continue;
      frame.unlabelled.push_back(p);
      frame.unlabelled_ids.push_back(static_cast<int>(m.id));
    }
    if (frame.unlabelled.empty())
      for (const natnet::Point& q : data.other_markers) {
        const Vec3 p = millimetres(q);
        if (!is_present(p)) continue;
        frame.unlabelled.push_back(p);
        frame.unlabelled_ids.push_back(-1);
      }
    frame.rate_hz = rate.add(data.frame_number, data.timestamp_s);

    frame.frame_number = static_cast<uint32_t>(data.frame_number);
    frame.capture_recording = (data.params & natnet::kFrameRecording) ? CaptureRecording::Recording
                                                                      : CaptureRecording::NotRecording;
    frame.source_time_ns = static_cast<int64_t>(std::llround(data.timestamp_s * 1e9));
    frame.capture_latency_ns = natnet::capture_latency_ns(data, server_info.clock_ticks_per_second);
    const natnet::TimecodeFields tc = natnet::split_timecode(data.timecode);
    frame.timecode.valid = data.timecode != 0 || data.timecode_subframe != 0;
    frame.timecode.hours = static_cast<uint8_t>(tc.hours);
    frame.timecode.minutes = static_cast<uint8_t>(tc.minutes);
    frame.timecode.seconds = static_cast<uint8_t>(tc.seconds);
    frame.timecode.frames = static_cast<uint8_t>(tc.frames);
    frame.timecode.subframe = static_cast<uint16_t>(data.timecode_subframe);
    frame.receive_time_ns = system_now_ns();
    reconnection.frame_arrived(where());
    sink.on_frame(frame);
  }

  // Silence is the only sign a UDP server has gone: no answer in the handshake, no frame while
  // streaming.
  void watch(uint64_t gen) {
    watchdog.expires_after(kWatchdogPeriod);
    watchdog.async_wait([self = shared_from_this(), gen](const boost::system::error_code& ec) {
      if (ec || self->stopped || gen != self->generation) return;
      const auto now = Clock::now();
      using std::chrono::duration_cast;
      using std::chrono::milliseconds;
      if (self->phase != Phase::Streaming && now - self->phase_start > self->options.reply_timeout)
        return self->fail(gen, std::string("no ") + (self->phase == Phase::ServerInfo ? "server info" : "model definitions") +
                                   " from " + self->where() + " within " +
                                   std::to_string(self->options.reply_timeout.count()) + " ms");
      if (self->phase == Phase::Streaming && self->options.stall_timeout.count() > 0 &&
          now - self->last_frame > self->options.stall_timeout)
        return self->fail(gen,
                          "stalled: no frame from " + self->where() + " for " +
                              std::to_string(duration_cast<milliseconds>(now - self->last_frame).count()) + " ms; reconnecting",
                          SourceState::Stalled);
      self->watch(gen);
    });
  }

  void keep_alive(uint64_t gen) {
    keep_alive_timer.expires_after(options.keep_alive_interval);
    keep_alive_timer.async_wait([self = shared_from_this(), gen](const boost::system::error_code& ec) {
      if (ec || self->stopped || gen != self->generation) return;
      self->send(natnet::encode_empty(natnet::message::KeepAlive));
      self->keep_alive(gen);
    });
  }

  void close_sockets() {
    boost::system::error_code ignored;
    resolver.cancel();
    watchdog.cancel();
    keep_alive_timer.cancel();
    if (command_socket.is_open() && phase == Phase::Streaming && !server_info.multicast)
      command_socket.send_to(asio::buffer(natnet::encode_empty(natnet::message::Disconnect)), server, 0, ignored);
    command_socket.close(ignored);
    data_socket.close(ignored);
  }

  void fail(uint64_t gen, const std::string& reason, SourceState reported = SourceState::Disconnected) {
    fail_connection(shared_from_this(), gen, reason, reported);
  }
};

NatNetSource::NatNetSource(asio::io_context& io, NatNetSourceOptions options, SourceSink& sink)
    : state_(std::make_shared<State>(io, std::move(options), sink)) {}

NatNetSource::~NatNetSource() { stop(); }

void NatNetSource::start() { start_source(state_); }
void NatNetSource::stop() { stop_source(state_); }

}  // namespace skinstream::server
