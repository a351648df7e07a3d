#include "server/ingest/qtm_source.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <unordered_map>

#include "protocol/qtm/qtm_command.h"
#include "protocol/qtm/qtm_labels.h"
#include "protocol/qtm/qtm_packet_framer.h"
#include "protocol/qtm/qtm_packet_reader.h"
#include "protocol/qtm/qtm_packet_writer.h"
#include "protocol/qtm/qtm_parameters.h"
#include "server/ingest/source_lifecycle.h"
#include "server/ingest/source_reconnection.h"
#include "server/system_clock.h"

namespace skinstream::server {
namespace {

constexpr size_t kQtmReadBytes = 64 * 1024;
const std::vector<std::string> kComponents = {"3D", "3DNoLabels"};

// Events after which QTM's labels may differ: the parameters are asked for again.
bool may_change_labels(qtm::Event event) {
  switch (event) {
    case qtm::Event::CaptureStarted:
    case qtm::Event::RtFromFileStarted:
    case qtm::Event::CameraSettingsChanged:
    case qtm::Event::CalibrationStopped:
      return true;
    default:
      return false;
  }
}

}  // namespace

struct QtmSource::State : std::enable_shared_from_this<QtmSource::State> {
  enum class Phase { Welcome, Version, Parameters, Streaming };

  State(asio::io_context& io_context, QtmSourceOptions opts, SourceSink& source_sink)
      : io(io_context),
        options(std::move(opts)),
        sink(source_sink),
        socket(io),
        udp_socket(io),
        resolver(io),
        stall_timer(io),
        handshake_timer(io),
        reconnection(io, sink, options.initial_backoff_seconds, options.max_backoff_seconds) {
    udp_buffer.resize(65536);  // one datagram at most
  }

  asio::io_context& io;
  QtmSourceOptions options;
  SourceSink& sink;
  tcp::socket socket;
  udp::socket udp_socket;
  tcp::resolver resolver;
  asio::steady_timer stall_timer, handshake_timer;
  SourceReconnection reconnection;
  qtm::PacketFramer framer;
  std::vector<unsigned char> udp_buffer;
  qtm::DataFrame data;
  SourceFrame frame;
  // Per QTM label (in the order of the 3D component): its subject and slot in frame.labelled.
  std::vector<std::pair<uint32_t, uint32_t>> label_slots;
  Phase phase = Phase::Welcome;
  bool have_labels = false;
  bool parameters_pending = false;  // a GetParameters is on its way; mismatching frames wait for it
  bool expecting_frames = false;    // StreamFrames sent and no NoMoreData since: silence is a stall
  std::chrono::steady_clock::time_point last_parameters_request{};
  uint64_t generation = 0;  // bumps with every connection: stale handlers see another one
  int64_t last_frame_ns = 0;
  std::atomic<bool> stopped{false};

  std::string where() const { return options.host + ":" + std::to_string(options.port); }

  void connect() {
    if (stopped) return;
    const uint64_t gen = ++generation;
    framer.reset();
    framer.reserve(2 * kQtmReadBytes);
    phase = Phase::Welcome;
    parameters_pending = false;
    expecting_frames = false;
    watch_handshake(gen);
    resolver.async_resolve(
        options.host, std::to_string(options.port),
        [self = shared_from_this(), gen](const boost::system::error_code& ec, const tcp::resolver::results_type& results) {
          if (self->stopped || gen != self->generation) return;
          if (ec) return self->fail(gen, "cannot resolve " + self->where() + ": " + ec.message());
          asio::async_connect(self->socket, results, [self, gen](const boost::system::error_code& ec2, const tcp::endpoint&) {
            if (self->stopped || gen != self->generation) return;
            if (ec2) return self->fail(gen, "cannot connect to " + self->where() + ": " + ec2.message());
            boost::system::error_code ignored;
            self->socket.set_option(tcp::no_delay(true), ignored);
            self->read(gen);
          });
        });
  }

  void read(uint64_t gen) {
    const auto room = framer.prepare(kQtmReadBytes);
    socket.async_read_some(asio::buffer(room.data(), room.size()),
                           [self = shared_from_this(), gen](const boost::system::error_code& ec, size_t n) {
                             self->on_read(gen, ec, n);
                           });
  }

  void on_read(uint64_t gen, const boost::system::error_code& ec, size_t n) {
    if (stopped || gen != generation) return;
    if (ec) {
      return fail(gen, (ec == asio::error::eof ? std::string("the server closed the connection")
                                               : "connection lost: " + ec.message()) +
                           " (" + where() + ")");
    }
    framer.commit(n);
    qtm::Bytes packet;
    for (;;) {
      const auto status = framer.next(packet);
      if (status == qtm::PacketFramer::Status::NeedMore) break;
      if (status == qtm::PacketFramer::Status::Error) {
        sink.on_bad_input("malformed_packet", "QTM: " + framer.error());
        return fail(gen, "malformed packet from " + where() + ": " + framer.error());
      }
      std::string error;
      if (!handle(gen, packet, error)) {
        sink.on_bad_input("malformed_packet", "QTM: " + error);
        return fail(gen, "bad answer from " + where() + ": " + error);
      }
      if (stopped || gen != generation) return;
    }
    read(gen);
  }

  // One packet from the server; false (with the reason) ends the connection.
  bool handle(uint64_t gen, qtm::Bytes packet, std::string& error) {
    uint32_t type = 0;
    if (!qtm::read_header(packet, type, error)) return false;
    switch (static_cast<qtm::PacketType>(type)) {
      case qtm::PacketType::Data:
        on_data(packet);
        return true;
      case qtm::PacketType::Command: {
        std::string text;
        if (!qtm::decode_text(packet, text, error)) return false;
        return on_command_reply(gen, text, error);
      }
      case qtm::PacketType::Xml: {
        std::string xml;
        if (!qtm::decode_text(packet, xml, error)) return false;
        return on_parameters(gen, xml, error);
      }
      case qtm::PacketType::Error: {
        std::string text;
        if (!qtm::decode_text(packet, text, error)) return false;
        if (phase != Phase::Streaming) {
          error = "QTM refused the handshake: " + text;
          return false;
        }
        sink.on_bad_input("qtm_error", "QTM answered with an error: " + text);
        return true;
      }
      case qtm::PacketType::Event: {
        qtm::Event event{};
        if (!qtm::decode_event(packet, event, error)) return false;
        if (phase == Phase::Streaming && may_change_labels(event)) ask_parameters(gen);
        // A capture in QTM is a take it records; "capture saved" ends one too.
        if (event == qtm::Event::CaptureStarted) frame.capture_recording = CaptureRecording::Recording;
        if (event == qtm::Event::CaptureStopped || event == qtm::Event::CaptureSaved)
          frame.capture_recording = CaptureRecording::NotRecording;
        return true;
      }
      case qtm::PacketType::NoMoreData:
        sink.on_source_state(SourceState::Finished, "QTM has no more frames (" + where() + ")");
        reconnection.frames_stopped();
        expecting_frames = false;  // until the next measurement: silence is expected
        return true;
      default:
        sink.on_bad_input("unknown_packet", std::string("QTM: skipping a packet of type ") + std::to_string(type) +
                                                " (" + qtm::packet_type_name(type) + ")");
        return true;
    }
  }

  bool on_command_reply(uint64_t gen, const std::string& text, std::string& error) {
    switch (phase) {
      case Phase::Welcome:
        if (text.rfind(qtm::kWelcome, 0) != 0) {
          error = "expected the welcome '" + std::string(qtm::kWelcome) + "', got '" + text.substr(0, 60) + "'";
          return false;
        }
        phase = Phase::Version;
        send(gen, qtm::encode_text(qtm::PacketType::Command, "Version 1." + std::to_string(qtm::kSpokenMinorVersion)));
        return true;
      case Phase::Version:
        if (text != "Version set to 1." + std::to_string(qtm::kSpokenMinorVersion)) {
          error = "QTM did not take protocol version 1." + std::to_string(qtm::kSpokenMinorVersion) + ": " +
                  text.substr(0, 60);
          return false;
        }
        phase = Phase::Parameters;
        ask_parameters(gen);
        return true;
      default:
        return true;  // answers to nothing we wait for (e.g. a late reply): nothing to do
    }
  }

  // While streaming, at most once per parameters_request_interval: a QTM whose frames keep
  // disagreeing with its own parameters was asked again after every frame.
  void ask_parameters(uint64_t gen) {
    if (parameters_pending) return;
    const auto now = std::chrono::steady_clock::now();
    if (phase == Phase::Streaming) {
      if (last_parameters_request != std::chrono::steady_clock::time_point{} &&
          now - last_parameters_request < options.parameters_request_interval)
        return;
      last_parameters_request = now;
    }
    parameters_pending = true;
    send(gen, qtm::encode_text(qtm::PacketType::Command, "GetParameters General 3D"));
  }

  bool on_parameters(uint64_t gen, const std::string& xml, std::string& error) {
    qtm::Parameters parameters;
    if (!qtm::parse_parameters_xml(xml, parameters, error)) return false;
    parameters_pending = false;
    if (!parameters.has_3d) {
      error = "QTM's parameters have no 3D section (is 3D tracking on?)";
      return false;
    }
    set_labels(parameters);
    if (phase == Phase::Parameters) {
      phase = Phase::Streaming;
      start_streaming(gen);
    }
    return true;
  }

  // Groups the labels by their actor prefix, in order of first appearance.
  void set_labels(const qtm::Parameters& parameters) {
    std::vector<SourceSubject> subjects;
    std::unordered_map<std::string_view, uint32_t> subject_of;
    label_slots.clear();
    for (const std::string& label : parameters.labels) {
      const qtm::SplitLabel split = qtm::split_label(label);
      auto [it, added] = subject_of.emplace(split.subject, static_cast<uint32_t>(subjects.size()));
      if (added) subjects.push_back({std::string(split.subject), {}});
      SourceSubject& subject = subjects[it->second];
      label_slots.emplace_back(it->second, static_cast<uint32_t>(subject.labels.size()));
      subject.labels.emplace_back(split.marker);
    }
    const bool changed = !have_labels || subjects.size() != frame.subjects.size() ||
                         !std::equal(subjects.begin(), subjects.end(), frame.subjects.begin(),
                                     [](const SourceSubject& a, const SourceSubject& b) {
                                       return a.name == b.name && a.labels == b.labels;
                                     });
    frame.rate_hz = parameters.frequency_hz;
    have_labels = true;
    if (!changed) return;
    frame.subjects = std::move(subjects);
    frame.labelled.resize(frame.subjects.size());
    for (size_t s = 0; s < frame.subjects.size(); ++s)
      frame.labelled[s].assign(frame.subjects[s].labels.size(), missing_point());
    ++frame.structure_version;
  }

  void start_streaming(uint64_t gen) {
    uint16_t udp_port = 0;
    if (options.udp_port > 0) {
      boost::system::error_code ec;
      if (!udp_socket.is_open()) {
        udp_socket.open(udp::v4(), ec);
        if (!ec) udp_socket.bind(udp::endpoint(udp::v4(), options.udp_port), ec);
        if (ec) {
          sink.on_bad_input("udp_bind", "QTM: cannot receive UDP on port " + std::to_string(options.udp_port) + ": " +
                                            ec.message() + "; streaming over TCP");
          udp_socket.close(ec);
        } else {
          receive_datagram();
        }
      }
      if (udp_socket.is_open()) udp_port = udp_socket.local_endpoint(ec).port();
    }
    send(gen, qtm::encode_text(qtm::PacketType::Command, qtm::stream_frames_command(kComponents, udp_port)));
    handshake_timer.cancel();
    last_frame_ns = system_now_ns();
    expecting_frames = true;
    watch_stall(gen);
  }

  void receive_datagram() {
    udp_socket.async_receive(asio::buffer(udp_buffer), [self = shared_from_this()](const boost::system::error_code& ec,
                                                                                    size_t n) {
      if (self->stopped || ec == asio::error::operation_aborted) return;
      if (!ec) {
        const qtm::Bytes packet(self->udp_buffer.data(), n);
        uint32_t type = 0;
        std::string error;
        if (!qtm::read_header(packet, type, error) || type != static_cast<uint32_t>(qtm::PacketType::Data))
          self->sink.on_bad_input("malformed_packet", "QTM UDP: " + (error.empty() ? "not a data packet" : error));
        else if (self->phase == Phase::Streaming)
          self->on_data(packet);
      }
      self->receive_datagram();
    });
  }

  void on_data(qtm::Bytes packet) {
    std::string error;
    if (!qtm::decode_data(packet, data, error)) {
      sink.on_bad_input("malformed_packet", "QTM: " + error);
      return;
    }
    if (!have_labels) return;  // frames before the labels cannot be read yet
    if (data.has_labelled && data.labelled.size() != label_slots.size()) {
      sink.on_bad_input("label_count_mismatch", "QTM frame " + std::to_string(data.frame_number) + " has " +
                                                    std::to_string(data.labelled.size()) + " labelled markers, the " +
                                                    "parameters name " + std::to_string(label_slots.size()) +
                                                    "; asking for them again");
      ask_parameters(generation);
      return;
    }
    int non_finite = 0;
    for (auto& subject : frame.labelled)
      for (Vec3& p : subject) p = missing_point();
    for (size_t i = 0; i < data.labelled.size(); ++i) {
      const auto& q = data.labelled[i];
      const Vec3 p(q[0], q[1], q[2]);
      if (!is_present(p)) {
        non_finite += !(std::isnan(q[0]) || std::isnan(q[1]) || std::isnan(q[2]));
        continue;
      }
      frame.labelled[label_slots[i].first][label_slots[i].second] = p;
    }
    frame.unlabelled.clear();
    frame.unlabelled_ids.clear();
    for (const qtm::UnlabelledMarker& m : data.unlabelled) {
      const Vec3 p(m.position[0], m.position[1], m.position[2]);
      if (!is_present(p)) {
        ++non_finite;
        continue;
      }
      frame.unlabelled.push_back(p);
      frame.unlabelled_ids.push_back(m.id <= static_cast<uint32_t>(INT32_MAX) ? static_cast<int>(m.id) : -1);
    }
    if (non_finite > 0)
      sink.on_bad_input("non_finite_point", "QTM frame " + std::to_string(data.frame_number) + ": " +
                                                std::to_string(non_finite) + " infinite coordinates, taken as missing");
    frame.frame_number = data.frame_number;
    frame.source_time_ns = data.timestamp_us * 1000;
    frame.receive_time_ns = last_frame_ns = system_now_ns();
    expecting_frames = true;
    reconnection.frame_arrived(where());
    sink.on_frame(frame);
  }

  // Checked a few times per stall_timeout, so a stall is seen within a quarter of it.
  void watch_stall(uint64_t gen) {
    if (options.stall_timeout.count() <= 0) return;
    stall_timer.expires_after(std::max<std::chrono::milliseconds>(options.stall_timeout / 4, std::chrono::milliseconds(10)));
    stall_timer.async_wait([self = shared_from_this(), gen](const boost::system::error_code& ec) {
      if (ec || self->stopped || gen != self->generation) return;
      const auto silent = std::chrono::nanoseconds(system_now_ns() - self->last_frame_ns);
      if (self->expecting_frames && silent > self->options.stall_timeout)
        return self->fail(gen,
                          "stalled: no frame from " + self->where() + " for " +
                              std::to_string(std::chrono::duration_cast<std::chrono::milliseconds>(silent).count()) +
                              " ms with the connection open; reconnecting",
                          SourceState::Stalled);
      self->watch_stall(gen);
    });
  }

  // From connecting to StreamFrames: a server that accepts and then says nothing (or stops
  // half-way) is left after handshake_timeout.
  void watch_handshake(uint64_t gen) {
    handshake_timer.expires_after(options.handshake_timeout);
    handshake_timer.async_wait([self = shared_from_this(), gen](const boost::system::error_code& ec) {
      if (ec || self->stopped || gen != self->generation || self->phase == Phase::Streaming) return;
      static const char* const kWaitingFor[] = {"the welcome", "the answer to Version", "the parameters", ""};
      self->fail(gen, "no handshake with " + self->where() + " within " + std::to_string(self->options.handshake_timeout.count()) +
                          " ms (waiting for " + kWaitingFor[static_cast<int>(self->phase)] + ")");
    });
  }

  // Commands are a few bytes, sent during the handshake or on a label change: never per frame.
  void send(uint64_t gen, std::vector<unsigned char> bytes) {
    auto buffer = std::make_shared<std::vector<unsigned char>>(std::move(bytes));
    asio::async_write(socket, asio::buffer(*buffer),
                      [self = shared_from_this(), gen, buffer](const boost::system::error_code& ec, size_t) {
                        if (ec && !self->stopped && gen == self->generation)
                          self->fail(gen, "cannot send to " + self->where() + ": " + ec.message());
                      });
  }

  void close_sockets() {
    boost::system::error_code ignored;
    resolver.cancel();
    stall_timer.cancel();
    handshake_timer.cancel();
    socket.shutdown(tcp::socket::shutdown_both, ignored);
    socket.close(ignored);
    udp_socket.close(ignored);
  }

  void fail(uint64_t gen, const std::string& reason, SourceState reported = SourceState::Disconnected) {
    fail_connection(shared_from_this(), gen, reason, reported);
  }
};

QtmSource::QtmSource(asio::io_context& io, QtmSourceOptions options, SourceSink& sink)
    : state_(std::make_shared<State>(io, std::move(options), sink)) {}

QtmSource::~QtmSource() { stop(); }

void QtmSource::start() { start_source(state_); }
void QtmSource::stop() { stop_source(state_); }

}  // namespace skinstream::server
