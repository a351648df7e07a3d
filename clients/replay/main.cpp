// skinstream-replay: streams recorded captures (C3D or TRC) as a Vicon DataStream server, so that
// skinstreamd, benchmarks and unmodified Vicon SDK clients can run without a capture stage. Several
// recordings stream as several subjects of one stream (a stage with several actors), each frame
// holding one frame of each.
//
//   skinstream-replay RECORDING... --port P [--rate HZ] [--speed X] [--loop | --hold]
//                     [--subject NAME]... [--multicast GROUP[:PORT]] [--multicast-ttl N] [--start-now]
//
// Prints one JSON line {"port": N} on stdout once listening (port 0 picks a free one); logs go to
// stderr. Errors are one line on stderr and a non-zero exit code.
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include "protocol/capture_file.h"
#include "protocol/file_error.h"
#include "server/asio.h"
#include "server/tcp_congestion.h"
#include "server/vicon/vicon_server.h"

namespace {

using namespace skinstream;

struct Arguments {
  std::vector<std::string> recordings;
  int port = vicon::kDefaultPort;
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
};

// "239.1.2.3:44801" or "239.1.2.3" -> address and port.
std::pair<std::string, uint16_t> split_address(const std::string& text) {
  const auto colon = text.rfind(':');
  if (colon == std::string::npos) return {text, vicon::kDefaultMulticastPort};
  const int port = std::stoi(text.substr(colon + 1));
  if (port <= 0 || port > 65535) throw std::invalid_argument("bad multicast port in " + text);
  return {text.substr(0, colon), static_cast<uint16_t>(port)};
}

// The recordings, read, each with the name of the subject it streams as.
struct Recordings {
  std::vector<Capture> captures;
  std::vector<vicon::CaptureSubject> subjects;
};

Recordings read_recordings(const Arguments& args) {
  if (!args.subjects.empty() && args.subjects.size() != args.recordings.size())
    throw std::invalid_argument("--subject is given " + std::to_string(args.subjects.size()) + " times for " +
                                std::to_string(args.recordings.size()) + " recordings: once per recording, or not at all");
  Recordings out;
  out.captures.reserve(args.recordings.size());  // the subjects point into it
  for (size_t r = 0; r < args.recordings.size(); ++r) {
    const std::string& path = args.recordings[r];
    const Capture& capture = out.captures.emplace_back(read_capture(path));
    if (capture.frame_count <= 0) throw FileError(path, "holds no frames");
    if (!(capture.rate_hz > 0.0) && !(args.rate > 0.0)) throw FileError(path, "has no frame rate; pass --rate");
    const std::string name = args.subjects.empty() ? std::filesystem::path(path).stem().string() : args.subjects[r];
    for (const vicon::CaptureSubject& other : out.subjects)
      if (other.name == name) throw std::invalid_argument("two recordings stream as subject \"" + name + "\": name each with --subject");
    out.subjects.push_back({&capture, name});
  }
  return out;
}

int run(const Arguments& args) {
  const Recordings recordings = read_recordings(args);
  server::ViconServerOptions options;
  options.bind_address = args.bind;
  options.port = static_cast<uint16_t>(args.port);
  options.rate_hz = args.rate;
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
  for (size_t r = 0; r < args.recordings.size(); ++r) {
    const Capture& capture = recordings.captures[r];
    spdlog::info("streaming {} ({} markers, {} frames at {} Hz, speed {}) as subject '{}' on {}:{}", args.recordings[r],
                 capture.point_count(), capture.frame_count, args.rate > 0.0 ? args.rate : capture.rate_hz, args.speed,
                 recordings.subjects[r].name, args.bind, vicon_server.port());
  }
  io.run();
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  spdlog::set_default_logger(spdlog::stderr_color_mt("replay"));
  Arguments args;
  CLI::App app{"skinstream-replay: stream recorded captures (C3D/TRC) as a Vicon DataStream server"};
  app.add_option("RECORDING", args.recordings, "capture files (.c3d or .trc), each streamed as one subject")->required();
  app.add_option("--port", args.port, "TCP port to listen on (0: pick a free one; printed as {\"port\": N})")
      ->check(CLI::Range(0, 65535))
      ->capture_default_str();
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
  app.add_option("--multicast", args.multicast, "also send every frame as UDP datagrams to GROUP[:PORT]");
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
      "The recording starts when the first client asks for a frame (RequestFrame), unless --start-now.\n"
      "Several recordings stream as several subjects, frame k of each in frame k of the stream; a subject\n"
      "is listed only in frames where its recording has a marker (it leaves the stage, and comes back).\n"
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
