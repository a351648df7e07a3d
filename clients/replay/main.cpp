// skinstream-replay: streams recorded captures (C3D or TRC) as a capture system would, so that
// skinstreamd, benchmarks and unmodified clients can run without a capture stage: a Vicon
// DataStream, QTM RT or NatNet server; several recordings become several subjects of one stream
// (a stage with several actors: server/replay/vicon/vicon_server.h, server/replay/qtm/qtm_server.h,
// server/replay/natnet/natnet_server.h).
//
//   skinstream-replay [--protocol vicon|qtm|natnet] RECORDING... --port P [--rate HZ] [--speed X]
//                     [--loop | --hold] [--subject NAME]... [--multicast GROUP[:PORT]] [--multicast-ttl N]
//                     [--start-now] [--unicast] [--multicast-interface ADDR] [--natnet-version 3.1|4.0|4.1]
//                     [--natnet-timestamp-jitter-us US] [--natnet-clock-hz HZ]
//
// Prints one JSON line {"port": N} on stdout once listening (port 0 picks a free one); logs go to
// stderr. Errors are one line on stderr and a non-zero exit code.
#include <csignal>
#include <cstdio>
#include <functional>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include "server/asio.h"
#include "server/replay/natnet/natnet_server.h"
#include "server/replay/qtm/qtm_server.h"
#include "server/replay/replay_recordings.h"
#include "server/tcp_congestion.h"
#include "server/replay/vicon/vicon_server.h"

namespace {

using namespace skinstream;

struct Arguments {
  std::string protocol = "vicon";
  std::vector<std::string> recordings;
  int port = -1;  // the protocol's own default
  std::string bind = "0.0.0.0";
  double rate = 0.0;
  double speed = 1.0;
  bool loop = false;
  bool hold = false;
  bool start_now = false;
  std::vector<std::string> subjects;  // one per recording, or none (the files' stems)
  std::string multicast;
  int multicast_ttl = 1;
  int max_queued = 4;
  std::string tcp_congestion;  // the system's
  bool unicast = false;           // NatNet
  std::string multicast_interface;  // NatNet: the interface multicast leaves by; empty: the system's
  std::string natnet_version = "4.1";
  double natnet_timestamp_jitter_us = 0.0;  // NatNet: a capture clock's jitter and resolution
  double natnet_capture_latency_us = 0.0;   // NatNet: the latency the frames' stamps report
  double natnet_clock_hz = 0.0;
};

// "239.1.2.3:44801" or "239.1.2.3" -> address and port.
std::pair<std::string, uint16_t> split_address(const std::string& text) {
  const auto colon = text.rfind(':');
  if (colon == std::string::npos) return {text, vicon::kDefaultMulticastPort};
  const int port = std::stoi(text.substr(colon + 1));
  if (port <= 0 || port > 65535) throw std::invalid_argument("bad multicast port in " + text);
  return {text.substr(0, colon), static_cast<uint16_t>(port)};
}

int run_qtm_or_natnet(const Arguments& args);

void log_streaming(const server::ReplayRecordings& recordings, const Arguments& args, uint16_t port) {
  for (const ReplaySubject& s : recordings.subjects)
    spdlog::info("streaming '{}' ({} markers, {} frames) at {} Hz, speed {}, as subject '{}' of a {} stream on {}:{}", s.name,
                 s.capture->point_count(), s.capture->frame_count, recordings.rate_hz, args.speed, s.name, args.protocol,
                 args.bind, port);
}

int run(const Arguments& args) {
  if (args.protocol != "vicon") return run_qtm_or_natnet(args);
  const server::ReplayRecordings recordings = server::load_replay_recordings(args.recordings, args.subjects, args.rate);

  server::ViconServerOptions options;
  options.bind_address = args.bind;
  options.port = static_cast<uint16_t>(args.port < 0 ? vicon::kDefaultPort : args.port);
  options.rate_hz = recordings.rate_hz;
  options.speed = args.speed;
  options.loop = args.loop;
  options.start_on_first_request = !args.start_now;
  options.max_queued_frames = static_cast<size_t>(args.max_queued);
  options.multicast_ttl = args.multicast_ttl;
  options.tcp_congestion = args.tcp_congestion;

  server::asio::io_context io;
  server::ViconServer vicon_server(io, recordings.subjects, options);
  vicon_server.start();  // throws with the address on failure

  // Without --loop or --hold: once the last frame is out, wait (up to 2 s) for the clients'
  // queues to drain, then exit 0.
  server::asio::steady_timer drain_timer(io);
  int drain_checks = 0;
  std::function<void()> drain = [&] {
    if (vicon_server.all_clients_idle() || ++drain_checks > 200) {
      spdlog::info("recording finished: {} frames produced, {} frame packets sent, {} dropped",
                   vicon_server.stats().frames_produced.load(), vicon_server.stats().frame_packets_sent.load(),
                   vicon_server.stats().frames_dropped.load());
      vicon_server.stop();
      io.stop();
      return;
    }
    drain_timer.expires_after(std::chrono::milliseconds(10));
    drain_timer.async_wait([&](const boost::system::error_code& ec) {
      if (!ec) drain();
    });
  };
  if (!args.loop && !args.hold) vicon_server.set_on_finished(drain);

  server::asio::signal_set signals(io, SIGINT, SIGTERM);
  signals.async_wait([&](const boost::system::error_code& ec, int signal_number) {
    if (ec) return;
    spdlog::info("signal {}: stopping", signal_number);
    vicon_server.stop();
    io.stop();
  });

  if (!args.multicast.empty()) {
    const auto [group, port] = split_address(args.multicast);
    vicon_server.start_multicast(group, port);
  }

  std::cout << "{\"port\": " << vicon_server.port() << "}" << std::endl;
  log_streaming(recordings, args, vicon_server.port());
  io.run();
  return 0;
}

// QTM RT and NatNet: several recordings as several subjects. Without --loop or --hold the
// program exits once the last frame has left (QTM: once every client's queue has drained, at
// most 2 s).
int run_qtm_or_natnet(const Arguments& args) {
  const server::ReplayRecordings recordings = server::load_replay_recordings(args.recordings, args.subjects, args.rate);
  server::asio::io_context io;
  std::unique_ptr<server::QtmServer> qtm;
  std::unique_ptr<server::NatNetServer> natnet;
  std::function<bool()> idle = [] { return true; };
  std::function<void()> stop;
  uint16_t port = 0;
  if (args.protocol == "qtm") {
    server::QtmServerOptions options;
    options.bind_address = args.bind;
    options.port = static_cast<uint16_t>(args.port < 0 ? qtm::kLittleEndianPort : args.port);
    options.rate_hz = recordings.rate_hz;
    options.speed = args.speed;
    options.loop = args.loop;
    options.start_on_first_request = !args.start_now;
    options.max_queued_frames = static_cast<size_t>(args.max_queued);
    qtm = std::make_unique<server::QtmServer>(io, recordings.subjects, options);
    qtm->start();
    port = qtm->port();
    idle = [&] { return qtm->all_clients_idle(); };
    stop = [&] { qtm->stop(); };
  } else {
    server::NatNetServerOptions options;
    options.bind_address = args.bind;
    options.command_port = static_cast<uint16_t>(args.port < 0 ? natnet::kCommandPort : args.port);
    options.multicast = !args.unicast;
    if (!args.multicast.empty()) {
      const auto [group, data_port] = split_address(args.multicast);
      options.multicast_group = group;
      if (args.multicast.find(':') != std::string::npos) options.data_port = data_port;
    }
    options.multicast_ttl = args.multicast_ttl;
    options.multicast_interface = args.multicast_interface;
    options.version = {args.natnet_version[0] - '0', args.natnet_version[2] - '0'};
    options.rate_hz = recordings.rate_hz;
    options.speed = args.speed;
    options.loop = args.loop;
    options.start_on_first_request = !args.start_now;
    options.timestamp_jitter_us = args.natnet_timestamp_jitter_us;
    options.timestamp_clock_hz = args.natnet_clock_hz;
    options.capture_latency_us = args.natnet_capture_latency_us;
    natnet = std::make_unique<server::NatNetServer>(io, recordings.subjects, options);
    natnet->start();
    port = natnet->command_port();
    stop = [&] { natnet->stop(); };
  }

  server::asio::steady_timer drain_timer(io);
  int drain_checks = 0;
  std::function<void()> drain = [&] {
    if (idle() || ++drain_checks > 200) {
      spdlog::info("recording finished");
      stop();
      io.stop();
      return;
    }
    drain_timer.expires_after(std::chrono::milliseconds(10));
    drain_timer.async_wait([&](const boost::system::error_code& ec) {
      if (!ec) drain();
    });
  };
  if (!args.loop && !args.hold) {
    if (qtm) qtm->set_on_finished(drain);
    if (natnet) natnet->set_on_finished(drain);
  }
  server::asio::signal_set signals(io, SIGINT, SIGTERM);
  signals.async_wait([&](const boost::system::error_code& ec, int signal_number) {
    if (ec) return;
    spdlog::info("signal {}: stopping", signal_number);
    stop();
    io.stop();
  });
  std::cout << "{\"port\": " << port << "}" << std::endl;
  log_streaming(recordings, args, port);
  io.run();
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  spdlog::set_default_logger(spdlog::stderr_color_mt("replay"));
  Arguments args;
  CLI::App app{"skinstream-replay: stream recorded captures (C3D/TRC) as a Vicon DataStream, QTM RT or NatNet server"};
  app.add_option("--protocol", args.protocol, "the capture system to stream as")
      ->check(CLI::IsMember({"vicon", "qtm", "natnet"}))
      ->capture_default_str();
  app.add_option("RECORDING", args.recordings, "capture files (.c3d or .trc); several: one subject each")->required();
  app.add_option("--port", args.port,
                 "port to listen on: TCP for vicon (801) and qtm (22223, little-endian), the UDP command port for "
                 "natnet (1510); 0: pick a free one; printed as {\"port\": N}")
      ->check(CLI::Range(0, 65535));
  app.add_option("--bind", args.bind, "address to listen on")->capture_default_str();
  app.add_option("--rate", args.rate, "frame rate to announce and stream, Hz (default: the recording's)")
      ->check(CLI::PositiveNumber);
  app.add_option("--speed", args.speed, "wall-clock speed factor (2: twice as fast)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  auto* loop = app.add_flag("--loop", args.loop, "start again after the last frame, forever (numbers keep rising)");
  app.add_flag("--hold", args.hold, "after the last frame, keep clients connected until SIGINT/SIGTERM")
      ->excludes(loop);
  app.add_flag("--start-now", args.start_now,
               "start the recording at once instead of when the first client asks for a frame");
  app.add_option("--subject", args.subjects, "subject name, once per recording in their order (default: each file's stem)")
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  app.add_option("--multicast", args.multicast,
                 "vicon: also send every frame as UDP datagrams to GROUP[:PORT]; natnet: the group and data port "
                 "(default 239.255.42.99:1511)");
  app.add_option("--multicast-interface", args.multicast_interface,
                 "natnet: address of the interface multicast frames leave by (default: the system's choice)");
  app.add_flag("--unicast", args.unicast, "natnet: send frames to each connected client instead of multicast");
  app.add_option("--natnet-version", args.natnet_version, "natnet: the NatNet layout streamed")
      ->check(CLI::IsMember({"3.0", "3.1", "4.0", "4.1"}))
      ->capture_default_str();
  app.add_option("--natnet-timestamp-jitter-us", args.natnet_timestamp_jitter_us,
                 "natnet: move each frame's timestamp by a random offset of up to +-this many microseconds, as a real "
                 "capture clock jitters")
      ->check(CLI::Range(0.0, 1e6));
  app.add_option("--natnet-clock-hz", args.natnet_clock_hz,
                 "natnet: round each frame's timestamp to the ticks of a clock of this frequency (e.g. 10000000)")
      ->check(CLI::Range(1.0, 1e12));
  app.add_option(
         "--natnet-capture-latency-us", args.natnet_capture_latency_us,
         "natnet: stamp each frame as transmitted this long after its cameras' mid-exposure (the capture "
         "system's own latency, which the daemon adds to its source-to-publish latency)")
      ->check(CLI::Range(0.0, 1e6));
  app.add_option("--multicast-ttl", args.multicast_ttl, "multicast TTL (hops)")
      ->check(CLI::Range(0, 255))
      ->capture_default_str();
  app.add_option("--max-queued", args.max_queued, "frames queued per client before the oldest is dropped")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  app.add_option("--tcp-congestion", args.tcp_congestion,
                 "TCP congestion control of client connections, e.g. reno (default: the system's)")
      ->check([](const std::string& name) {
        return name.empty() || skinstream::server::is_tcp_congestion_name(name) ? std::string()
                                                                               : "not a congestion control name: " + name;
      })
      ->capture_default_str();
  app.footer(
      "The recording starts when the first client asks for frames (vicon: RequestFrame, qtm: StreamFrames,\n"
      "natnet: CONNECT), unless --start-now.\n"
      "Several recordings stream as several subjects, frame k of each in frame k of the stream; a Vicon\n"
      "subject is listed only in frames where its recording has a marker (it leaves the stage, and comes back).\n"
      "Without --loop or --hold the program exits 0 once the last frame has been sent to the connected\n"
      "clients. SIGINT/SIGTERM stop it cleanly (exit 0).");
  CLI11_PARSE(app, argc, argv);

  try {
    return run(args);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
