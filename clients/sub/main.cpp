// skinstream-sub: subscribes to a skinstreamd (through the C++ client library), prints rates and
// latency, and can save frames as PLY or record them as a PC2 point cache. With --json: one JSON
// line per frame, then a summary line.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>

#include "protocol/meshes/mesh_ply.h"
#include "protocol/offline/point_cache.h"
#include "protocol/printable_text.h"
#include "protocol/subscriber/datagram_authentication.h"
#include "skinstream/client.h"

namespace {

using namespace skinstream;

struct Percentiles {
  std::vector<double> values;
  double at(double q) {
    if (values.empty()) return 0.0;
    std::sort(values.begin(), values.end());
    return values[std::min(values.size() - 1, static_cast<size_t>(q * (values.size() - 1) + 0.5))];
  }
  nlohmann::json summary() {
    return {{"p50_ms", at(0.5)}, {"p99_ms", at(0.99)}, {"max_ms", values.empty() ? 0.0 : *std::max_element(values.begin(), values.end())}, {"count", values.size()}};
  }
};

// "HOST:PORT" -> host, port; throws std::invalid_argument.
std::pair<std::string, uint16_t> split_host_port(const std::string& address) {
  const size_t colon = address.rfind(':');
  if (colon == std::string::npos || colon == 0 || colon + 1 == address.size())
    throw std::invalid_argument("\"" + address + "\" is not HOST:PORT");
  const std::string port = address.substr(colon + 1);
  if (port.find_first_not_of("0123456789") != std::string::npos || port.size() > 5 || std::stoi(port) < 1 || std::stoi(port) > 65535)
    throw std::invalid_argument("\"" + address + "\": the port must be 1-65535");
  return {address.substr(0, colon), static_cast<uint16_t>(std::stoi(port))};
}

std::vector<Vec3> to_points(std::span<const float> xyz) {
  std::vector<Vec3> points(xyz.size() / 3);
  for (size_t v = 0; v < points.size(); ++v) points[v] = Vec3(xyz[3 * v], xyz[3 * v + 1], xyz[3 * v + 2]);
  return points;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"skinstream-sub: subscribe to skinstreamd and report what arrives"};
  std::string address, save_dir, encoding_name, record_path, subject, token, multicast, multicast_interface = "0.0.0.0";
  uint32_t multicast_stream = 0;
  bool normals = false, quantised = false, markers = false, no_mesh = false, stats = false, json = false,
       evaluate = false, paced = false, plain_first_contact = false;
  long frames_wanted = 0;
  int save_every = 0, protocol = 2;
  app.add_option("ADDRESS", address, "HOST:PORT of the daemon's subscriber port")->required();
  app.add_option("--encoding", encoding_name, "how positions travel: float (default), quantised, compressed or parameters")
      ->check(CLI::IsMember({"float", "quantised", "compressed", "parameters"}));
  app.add_flag("--evaluate", evaluate,
               "parameters: evaluate them into vertices here (the time counts in the latency; implied by --save-every and --record)");
  app.add_flag("--normals", normals, "ask for vertex normals (parameters: computed here)");
  app.add_flag("--quantised", quantised, "the quantised encoding (as --encoding quantised)");
  app.add_flag("--markers", markers, "ask for the filled markers and their status");
  app.add_flag("--no-mesh", no_mesh, "markers only, no vertex positions");
  app.add_flag("--paced", paced, "acknowledge each frame: at most 2 in flight");
  app.add_flag(
      "--plain-first-contact", plain_first_contact,
      "ask for MeshInfo and the Model plain (default: packed, about 2.8 times fewer bytes; protocol 2)");
  app.add_option("--subject", subject, "the subject's name (protocol 2; default: the daemon's first)");
  std::string token_file;
  double timeout_seconds = 10.0;
  uint32_t max_vertices = client::Options{}.max_vertices, max_markers = client::Options{}.max_markers;
  app.add_option("--token-file", token_file,
                 "the daemon's shared token, when it has one: this file's first line (or the environment's SKINSTREAM_TOKEN)");
  app.add_option("--token", token, "the token itself (seen by anyone who lists the processes: prefer --token-file)");
  app.add_option("--timeout", timeout_seconds,
                 "seconds without a word from the daemon (it speaks every second) before giving up with an error; 0: wait for ever")
      ->check(CLI::Range(0.0, 86400.0));
  app.add_option("--max-vertices", max_vertices, "the largest mesh taken (a MeshInfo announcing more is an error)");
  app.add_option("--max-markers", max_markers, "the most markers taken");
  app.add_option("--protocol", protocol, "subscriber protocol version: 2 (default) or 1 (float and quantised only)")->check(CLI::Range(1, 2));
  app.add_option("--multicast", multicast,
                 "GROUP:PORT: the parameters of every frame from the daemon's multicast group (its "
                 "--multicast; --evaluate "
                 "turns them into vertices); MeshInfo and the Model from the daemon's offer on PORT + 1, "
                 "else from ADDRESS over TCP");
  app.add_option("--multicast-interface", multicast_interface, "multicast: this host's IPv4 address to join the group on");
  app.add_option("--multicast-stream", multicast_stream, "multicast: the subject's stream id (0: the daemon's first)");
  bool wait_for_stdin = false;
  app.add_flag("--start-at-stdin-end", wait_for_stdin,
               "connect only once standard input ends (a load generator's processes, started beforehand, "
               "join together when it closes their pipes), and exit without connecting if anything is "
               "written to it first; first_frame_seconds counts from then");
  bool multicast_no_offer = false;
  app.add_flag("--multicast-no-offer", multicast_no_offer,
               "multicast: fetch MeshInfo and the Model over TCP, not from the daemon's offer");
  std::string multicast_key_file;
  app.add_option("--multicast-key-file", multicast_key_file,
                 "multicast: take only datagrams signed with the key on this file's first line (the daemon's multicast_key_file)");
  app.add_option("--frames", frames_wanted, "exit after this many frames (0 = run until the daemon closes)");
  std::vector<std::string> save_arguments;
  app.add_option("--save-every", save_arguments, "N DIR: save every Nth frame as DIR/frame_<frame number>.ply")->expected(2);
  app.add_option("--record", record_path, "FILE.pc2: record every frame's vertices as a PC2 point cache (Blender's Mesh Cache modifier)");
  app.add_flag("--stats", stats, "print rates and latency once a second");
  app.add_flag("--json", json, "JSON: one line per frame, then a summary");
  CLI11_PARSE(app, argc, argv);
  if (!save_arguments.empty()) {
    try {
      save_every = std::stoi(save_arguments[0]);
    } catch (const std::exception&) {
      save_every = -1;
    }
    save_dir = save_arguments[1];
    if (save_every <= 0) {
      std::fprintf(stderr, "skinstream-sub: error: --save-every N DIR: N must be a positive number\n");
      return 1;
    }
  }
  if (quantised && !encoding_name.empty() && encoding_name != "quantised") {
    std::fprintf(stderr, "skinstream-sub: error: --quantised and --encoding %s disagree\n", encoding_name.c_str());
    return 1;
  }
  try {
    client::Options options;
    std::tie(options.host, options.port) = split_host_port(address);
    options.encoding = quantised ? client::Encoding::Quantised
                                 : (encoding_name.empty() ? client::Encoding::Float : client::encoding_from_string(encoding_name));
    options.normals = normals;
    options.markers = markers;
    options.mesh = !no_mesh;
    options.paced = paced;
    options.packed = !plain_first_contact;
    options.evaluate = evaluate || save_every > 0 || !record_path.empty();
    options.subject = subject;
    if (!token_file.empty()) {
      std::ifstream in(token_file);
      if (!in || !std::getline(in, token)) throw std::runtime_error(token_file + ": cannot read the token (its first line)");
      if (!token.empty() && token.back() == '\r') token.pop_back();
    } else if (token.empty()) {
      if (const char* from_environment = std::getenv("SKINSTREAM_TOKEN")) token = from_environment;
    }
    options.token = token;
    options.silence_timeout = std::chrono::milliseconds(static_cast<long long>(timeout_seconds * 1000.0));
    options.max_vertices = max_vertices;
    options.max_markers = max_markers;
    options.protocol_version = protocol;
    if (!multicast.empty()) {
      if (!encoding_name.empty() && encoding_name != "parameters") throw std::invalid_argument("--multicast carries the parameters encoding only");
      std::tie(options.multicast.group, options.multicast.port) = split_host_port(multicast);
      options.multicast.interface_address = multicast_interface;
      options.multicast.stream_id = multicast_stream;
      options.multicast.offer = !multicast_no_offer;
      if (!multicast_key_file.empty()) {
        const std::vector<unsigned char> key = subscriber::read_datagram_key_file(multicast_key_file);
        options.multicast.key.assign(key.begin(), key.end());
      }
      options.encoding = client::Encoding::Parameters;
    }
    if (save_every > 0) std::filesystem::create_directories(save_dir);
    if (wait_for_stdin && std::fgetc(stdin) != EOF) {
      std::fprintf(stderr, "skinstream-sub: told to stop before it started\n");
      return 0;
    }
    const auto connecting = std::chrono::steady_clock::now();
    client::Subscriber sub(options);

    std::unique_ptr<PointCacheWriter> recording;
    long frames = 0, out_of_order = 0, saved = 0;
    int64_t last_frame_number = -1;
    uint32_t pipeline_dropped = 0, subscriber_dropped = 0;
    uint64_t frame_bytes = 0;
    bool announced = false;
    std::chrono::steady_clock::time_point first_frame_at{}, last_frame_at{};
    uint64_t bytes_before_first_frame = 0;
    uint32_t subscriber_dropped_before_first = 0;  // while MeshInfo and the Model were on their way
    Percentiles since_publish, since_receive, end_to_end, decode;
    const auto start = std::chrono::steady_clock::now();
    auto last_report = start;
    long frames_at_report = 0;
    bool finished = false;
    client::Frame frame;
    // A frame the daemon sent broken is skipped by the library: said here, at most once a second.
    uint64_t rejections_reported = 0;
    auto last_rejection_report = start - std::chrono::seconds(1);
    auto report_rejections = [&] {
      const uint64_t rejected = sub.frames_rejected();
      const auto now = std::chrono::steady_clock::now();
      if (rejected == rejections_reported || now - last_rejection_report < std::chrono::seconds(1)) return;
      std::fprintf(stderr, "skinstream-sub: warning: %s (%llu frames skipped so far)\n", sub.last_rejection().c_str(),
                   static_cast<unsigned long long>(rejected));
      rejections_reported = rejected;
      last_rejection_report = now;
    };
    for (;;) {
      try {
        const bool got = sub.next(frame, std::chrono::seconds(1));
        report_rejections();
        if (!got) continue;
      } catch (const client::Error& e) {
        const std::string what = e.what();
        if (what.find("closed the connection") == std::string::npos) throw;
        finished = true;  // the daemon stopped: a normal end
        break;
      }
      const client::Mesh& mesh = sub.mesh();
      if (!announced) {
        announced = true;
        first_frame_at = std::chrono::steady_clock::now();
        bytes_before_first_frame = sub.bytes_received();
        subscriber_dropped_before_first = frame.subscriber_dropped;
        if (!json)
          std::printf("mesh: %u vertices, %zu faces, %zu markers, %u parts, %.2f Hz, subject \"%s\", encoding %s%s\n", mesh.vertex_count,
                      mesh.indices.size() / 3, mesh.marker_names.size(), mesh.part_count, mesh.source_rate_hz, printable_text(mesh.subject).c_str(),
                      client::to_string(mesh.encoding),
                      sub.model_bytes() ? (", model " + std::to_string(sub.model_bytes()) + " bytes").c_str() : "");
        if (!record_path.empty()) {
          if (mesh.vertex_count == 0) throw std::runtime_error("--record: the daemon sends no vertices");
          recording = std::make_unique<PointCacheWriter>(record_path, static_cast<int>(mesh.vertex_count));
        }
      }
      ++frames;
      last_frame_at = std::chrono::steady_clock::now();
      frame_bytes += frame.message_bytes;
      if (static_cast<int64_t>(frame.frame_number) <= last_frame_number) ++out_of_order;
      last_frame_number = frame.frame_number;
      pipeline_dropped = frame.pipeline_dropped;
      subscriber_dropped = frame.subscriber_dropped;
      // Latency to the moment the frame could be drawn: decoding (and evaluating) included.
      const int64_t ready = frame.ready_time_ns;
      since_publish.values.push_back((ready - frame.publish_time_ns) * 1e-6);
      since_receive.values.push_back((ready - frame.receive_time_ns) * 1e-6);
      decode.values.push_back((ready - frame.arrival_time_ns) * 1e-6);
      // A source timestamp after 2001 is wall-clock time, so end to end is measurable.
      const bool wall_clock_source = frame.source_time_ns > 1'000'000'000'000'000'000;
      if (wall_clock_source) end_to_end.values.push_back((ready - frame.source_time_ns) * 1e-6);
      if (json) {
        nlohmann::json line = {{"frame", frame.frame_number},
                               {"source_time_ns", frame.source_time_ns},
                               {"receive_time_ns", frame.receive_time_ns},
                               {"publish_time_ns", frame.publish_time_ns},
                               {"arrival_time_ns", frame.arrival_time_ns},
                               {"ready_time_ns", frame.ready_time_ns},
                               {"bytes", frame.message_bytes},
                               {"vertices", frame.positions.size() / 3},
                               {"filled", frame.markers_filled},
                               {"relabelled", frame.markers_relabelled},
                               {"pipeline_dropped", frame.pipeline_dropped},
                               {"subscriber_dropped", frame.subscriber_dropped}};
        if (frame.timecode.valid) {
          char text[32];
          std::snprintf(text, sizeof text, "%02d:%02d:%02d%c%02d", frame.timecode.hours, frame.timecode.minutes, frame.timecode.seconds,
                        frame.timecode.drop_frame ? ';' : ':', frame.timecode.frames);
          line["timecode"] = {{"text", text}, {"subframe", frame.timecode.subframe}, {"rate_hz", frame.timecode.rate_hz}};
        }
        if (!frame.markers.empty()) {
          line["markers"] = std::vector<float>(frame.markers.begin(), frame.markers.end());
          line["status"] = std::vector<uint8_t>(frame.marker_status.begin(), frame.marker_status.end());
        }
        std::printf("%s\n", line.dump().c_str());
      }
      if (save_every > 0 && frames % save_every == 0 && !frame.positions.empty()) {
        std::vector<Face> faces;
        for (size_t i = 0; i + 2 < mesh.indices.size(); i += 3)
          faces.push_back({static_cast<int>(mesh.indices[i]), static_cast<int>(mesh.indices[i + 1]), static_cast<int>(mesh.indices[i + 2]), -1});
        char name[64];
        std::snprintf(name, sizeof name, "frame_%06u.ply", frame.frame_number);
        write_ply((std::filesystem::path(save_dir) / name).string(), to_points(frame.positions), faces);
        ++saved;
      }
      if (recording && !frame.positions.empty()) recording->append(to_points(frame.positions));
      const auto t = std::chrono::steady_clock::now();
      if (stats && !json && t - last_report >= std::chrono::seconds(1)) {
        const double seconds = std::chrono::duration<double>(t - last_report).count();
        std::printf("%.1f frames/s, %.2f MB/s total, latency since publish p50 %.2f ms, since receive p50 %.2f ms, dropped %u/%u\n",
                    (frames - frames_at_report) / seconds, sub.bytes_received() / 1e6 / std::chrono::duration<double>(t - start).count(),
                    since_publish.at(0.5), since_receive.at(0.5), pipeline_dropped, subscriber_dropped);
        std::fflush(stdout);
        last_report = t;
        frames_at_report = frames;
      }
      if (frames_wanted > 0 && frames >= frames_wanted) break;
    }
    if (recording) recording->close();
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    nlohmann::json summary = {
        {"frames", frames},
        {"out_of_order", out_of_order},
        {"seconds", seconds},
        {"frames_per_second", seconds > 0 ? frames / seconds : 0.0},
        {"megabytes", sub.bytes_received() / 1e6},
        // From connecting: MeshInfo and the Model included.
        {"first_frame_seconds",
         frames > 0 ? std::chrono::duration<double>(first_frame_at - connecting).count() : 0.0},
        // Once in: its wait for MeshInfo and the Model left out.
        {"frames_per_second_after_first",
         frames > 1 ? (frames - 1) / std::chrono::duration<double>(last_frame_at - first_frame_at).count()
                    : 0.0},
        {"bytes_before_first_frame", bytes_before_first_frame},
        {"encoding", sub.has_mesh() ? client::to_string(sub.mesh().encoding) : "none"},
        {"bytes_per_frame", frames > 0 ? static_cast<double>(frame_bytes) / frames : 0.0},
        {"model_bytes", sub.model_bytes()},
        {"meshes_received", sub.meshes_received()},
        {"frames_skipped", sub.frames_skipped()},
        {"frames_rejected", sub.frames_rejected()},
        {"pipeline_dropped", pipeline_dropped},
        {"subscriber_dropped", subscriber_dropped},
        {"subscriber_dropped_after_first", subscriber_dropped - subscriber_dropped_before_first},
        {"saved", saved},
        {"recorded", recording ? recording->sample_count() : 0},
        {"decode", decode.summary()},
        {"latency_since_publish", since_publish.summary()},
        {"latency_since_receive", since_receive.summary()}};
    if (!end_to_end.values.empty()) summary["latency_end_to_end"] = end_to_end.summary();
    if (!multicast.empty()) {
      const client::MulticastStats m = sub.multicast_stats();
      summary["multicast"] = {{"datagrams", m.datagrams},
                              {"frames_completed", m.frames_completed},
                              {"frames_lost", m.frames_lost},
                              {"frames_incomplete", m.frames_incomplete},
                              {"datagrams_rejected", m.datagrams_rejected},
                              {"datagrams_other_stream", m.datagrams_other_stream},
                              {"datagrams_late", m.datagrams_late},
                              {"datagrams_duplicate", m.datagrams_duplicate},
                              {"frames_superseded", m.frames_superseded},
                              {"messages_rejected", m.messages_rejected},
                              {"datagrams_out_of_window", m.datagrams_out_of_window},
                              {"datagrams_unauthenticated", m.datagrams_unauthenticated},
                              {"resyncs", m.resyncs},
                              {"frames_other_model", m.frames_other_model},
                              {"model_fetches", m.model_fetches},
                              {"offer_datagrams", m.offer_datagrams},
                              {"offers_taken", m.offers_taken},
                              {"offers_rejected", m.offers_rejected},
                              {"offer_timeouts", m.offer_timeouts},
                              {"last_error", m.last_error}};
    }
    if (json) std::printf("%s\n", nlohmann::json{{"summary", summary}}.dump().c_str());
    else std::printf("%s\n", summary.dump(2).c_str());
    if (finished && frames_wanted > 0 && frames < frames_wanted) {
      std::fprintf(stderr, "skinstream-sub: error: the daemon closed the connection after %ld of %ld frames\n", frames, frames_wanted);
      return 1;
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "skinstream-sub: error: %s\n", e.what());
    return 1;
  }
}
