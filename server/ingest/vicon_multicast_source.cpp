#include "server/ingest/vicon_multicast_source.h"

#include <atomic>
#include <chrono>

#include "protocol/vicon/vicon_packet_reader.h"
#include "server/ingest/vicon_source.h"
#include "server/system_clock.h"

namespace skinstream::server {

struct ViconMulticastSource::State : std::enable_shared_from_this<ViconMulticastSource::State> {
  State(asio::io_context& io_context, ViconMulticastSourceOptions opts, SourceSink& frame_sink)
      : io(io_context),
        options(std::move(opts)),
        sink(frame_sink),
        assembler(frame_sink, options.limits),
        socket(io),
        silence_timer(io),
        datagram(64 * 1024) {
    objects.reserve(16);
  }

  asio::io_context& io;
  ViconMulticastSourceOptions options;
  SourceSink& sink;
  ViconFrameAssembler assembler;
  udp::socket socket;
  asio::steady_timer silence_timer;
  std::vector<unsigned char> datagram;
  std::vector<vicon::ObjectView> objects;
  udp::endpoint sender;
  bool streaming = false;
  std::atomic<uint16_t> port{0};
  std::atomic<bool> stopped{false};

  std::string where() const { return options.group + ":" + std::to_string(options.port); }

  void open() {
    boost::system::error_code ec;
    const auto group = asio::ip::make_address(options.group, ec);
    const auto interface = ec ? asio::ip::address() : asio::ip::make_address(options.interface_address, ec);
    // A socket bound to a unicast address does not see datagrams sent to a group: bind "any" then.
    const udp::endpoint local(group.is_multicast() ? asio::ip::address(asio::ip::address_v4::any()) : group,
                              options.port);
    if (!ec) socket.open(local.protocol(), ec);
    if (!ec) socket.set_option(udp::socket::reuse_address(true), ec);
    if (!ec) socket.bind(local, ec);
    if (!ec && group.is_multicast()) {
      if (group.is_v4() && interface.is_v4())
        socket.set_option(asio::ip::multicast::join_group(group.to_v4(), interface.to_v4()), ec);
      else
        socket.set_option(asio::ip::multicast::join_group(group), ec);
    }
    if (ec) {
      sink.on_source_state(SourceState::Disconnected, "cannot receive on " + where() + ": " + ec.message());
      return;
    }
    port = socket.local_endpoint(ec).port();
    sink.on_source_state(SourceState::Connecting, "listening on " + where());
    receive();
  }

  void receive() {
    socket.async_receive_from(asio::buffer(datagram), sender,
                              [self = shared_from_this()](const boost::system::error_code& ec, size_t n) {
                                self->on_datagram(ec, n);
                              });
  }

  void on_datagram(const boost::system::error_code& ec, size_t n) {
    if (stopped) return;
    if (ec) {
      if (ec == asio::error::operation_aborted) return;
      sink.on_bad_input("short_read", "datagram receive failed: " + ec.message());
      receive();
      return;
    }
    const int64_t now = system_now_ns();
    std::string error;
    const vicon::Bytes packet(datagram.data(), n);
    auto result = ViconFrameAssembler::Result::Malformed;
    if (vicon::split_objects(packet, objects, error, options.limits)) result = assembler.handle(objects, now, error);
    if (stopped) return;
    if (result == ViconFrameAssembler::Result::Malformed) {
      sink.on_bad_input("malformed_packet", "datagram of " + std::to_string(n) + " bytes: " + error);
    } else if (result == ViconFrameAssembler::Result::Frame) {
      if (!streaming) {
        streaming = true;
        sink.on_source_state(SourceState::Streaming, where());
      }
      arm_silence_timer();
      sink.on_frame(assembler.frame());
    }
    if (!stopped) receive();
  }

  void arm_silence_timer() {
    silence_timer.expires_after(std::chrono::duration_cast<std::chrono::steady_clock::duration>(
        std::chrono::duration<double>(options.silence_timeout_seconds)));
    silence_timer.async_wait([self = shared_from_this()](const boost::system::error_code& ec) {
      if (ec || self->stopped || !self->streaming) return;
      self->streaming = false;
      self->sink.on_source_state(SourceState::Disconnected, "no datagram on " + self->where() + " for " +
                                                                std::to_string(self->options.silence_timeout_seconds) +
                                                                " s");
    });
  }
};

ViconMulticastSource::ViconMulticastSource(asio::io_context& io, ViconMulticastSourceOptions options, SourceSink& sink)
    : state_(std::make_shared<State>(io, std::move(options), sink)) {}

ViconMulticastSource::~ViconMulticastSource() { stop(); }

void ViconMulticastSource::start() {
  asio::post(state_->io, [state = state_] {
    if (!state->stopped) state->open();
  });
}

void ViconMulticastSource::stop() {
  if (state_->stopped.exchange(true)) return;
  asio::post(state_->io, [state = state_] {
    boost::system::error_code ignored;
    state->silence_timer.cancel();
    state->socket.close(ignored);
  });
}

uint16_t ViconMulticastSource::bound_port() const { return state_->port; }

}  // namespace skinstream::server
