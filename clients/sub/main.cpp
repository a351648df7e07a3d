// skinstream-sub: subscribes to a skinstreamd over TCP, prints rates and latency, and can save
// frames as PLY. With --json: one JSON line per frame, then a summary line.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <nlohmann/json.hpp>

#include "server/client/subscriber_client.h"
#include "protocol/mesh_ply.h"

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

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"skinstream-sub: subscribe to skinstreamd and report what arrives"};
  std::string address, save_dir;
  bool normals = false, quantised = false, markers = false, no_mesh = false, stats = false, json = false;
  long frames_wanted = 0;
  int save_every = 0;
  app.add_option("ADDRESS", address, "HOST:PORT of the daemon's subscriber port")->required();
  app.add_flag("--normals", normals, "ask for vertex normals");
  app.add_flag("--quantised", quantised, "ask for the quantised encoding");
  app.add_flag("--markers", markers, "ask for the filled markers and their status");
  app.add_flag("--no-mesh", no_mesh, "markers only, no vertex positions");
  app.add_option("--frames", frames_wanted, "exit after this many frames (0 = run until the daemon closes)");
  std::vector<std::string> save_arguments;
  app.add_option("--save-every", save_arguments, "N DIR: save every Nth frame as DIR/frame_<frame number>.ply")->expected(2);
  std::optional<std::string> subject;
  app.add_option("--subject", subject,
                 "the subject to follow on a daemon serving several (protocol version 2; \"\" = the first)");
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
  try {
    const auto [host, port] = sub::split_host_port(address);
    const uint32_t wants = (normals ? subscriber::kWantNormals : 0) | (markers ? subscriber::kWantMarkers : 0) |
                           (no_mesh ? subscriber::kWantNoMesh : 0);
    // Version 1 unless a subject is named; version 2 says the encoding apart from the wants.
    subscriber::Hello hello{.wants = wants | (quantised ? subscriber::kWantQuantised : 0)};
    if (subject)
      hello = {.wants = wants,
               .version = subscriber::kVersion2,
               .encoding = static_cast<uint32_t>(quantised ? subscriber::Encoding::Quantised : subscriber::Encoding::Float),
               .subject = *subject};
    const uint16_t version = hello.version;
    if (save_every > 0) std::filesystem::create_directories(save_dir);
    sub::SubscriberClient client(host, port, hello);
    std::string refused;  // the daemon's reason, when it refused this subscriber

    std::vector<synth::Face> faces;
    long frames = 0, out_of_order = 0, saved = 0;
    uint64_t bytes = 0;
    int64_t last_frame_number = -1;
    uint32_t pipeline_dropped = 0, subscriber_dropped = 0;
    Percentiles since_publish, since_receive, end_to_end;
    const auto start = std::chrono::steady_clock::now();
    auto last_report = start;
    long frames_at_report = 0;
    const bool finished = client.run([&](subscriber::MessageType type, std::span<const unsigned char> payload, int64_t now) {
      bytes += payload.size() + subscriber::kHeaderBytes;
      if (type == subscriber::MessageType::MeshInfo) {
        const subscriber::MeshInfo info = subscriber::decode_mesh_info(payload, version);
        faces.clear();
        for (const auto& f : info.faces) faces.push_back({static_cast<int>(f[0]), static_cast<int>(f[1]), static_cast<int>(f[2]), -1});
        if (!json)
          std::printf("mesh: %u vertices, %zu faces, %u markers, %u parts, %.2f Hz\n", info.vertex_count, info.faces.size(),
                      info.marker_count, info.part_count, info.source_rate_hz);
        return true;
      }
      if (type == subscriber::MessageType::Status) {
        const subscriber::Status status = subscriber::decode_status(payload, version);
        if (status.state == subscriber::SourceStateCode::Refused) {
          refused = status.detail;
          return false;
        }
        if (!json && stats)
          std::printf("status: state %u, %.2f Hz, received %llu, published %llu, %s\n", static_cast<unsigned>(status.state),
                      status.source_rate_hz, static_cast<unsigned long long>(status.frames_received),
                      static_cast<unsigned long long>(status.frames_published), status.detail.c_str());
        return true;
      }
      if (type != subscriber::MessageType::Frame) return true;
      const subscriber::Frame frame = subscriber::decode_frame(payload, version);
      const subscriber::FrameInfo& info = frame.info;
      ++frames;
      if (static_cast<int64_t>(info.frame_number) <= last_frame_number) ++out_of_order;
      last_frame_number = info.frame_number;
      pipeline_dropped = info.pipeline_dropped;
      subscriber_dropped = info.subscriber_dropped;
      since_publish.values.push_back((now - info.publish_time_ns) * 1e-6);
      since_receive.values.push_back((now - info.receive_time_ns) * 1e-6);
      // A source timestamp after 2001 is wall-clock time, so end to end is measurable.
      const bool wall_clock_source = info.source_time_ns > 1'000'000'000'000'000'000;
      if (wall_clock_source) end_to_end.values.push_back((now - info.source_time_ns) * 1e-6);
      if (json) {
        nlohmann::json line = {{"frame", info.frame_number},
                               {"flags", info.flags},
                               {"source_time_ns", info.source_time_ns},
                               {"receive_time_ns", info.receive_time_ns},
                               {"publish_time_ns", info.publish_time_ns},
                               {"arrival_time_ns", now},
                               {"vertices", info.vertex_count},
                               {"filled", info.markers_filled},
                               {"relabelled", info.markers_relabelled},
                               {"pipeline_dropped", info.pipeline_dropped},
                               {"subscriber_dropped", info.subscriber_dropped}};
        if (!frame.markers.empty()) {
          line["markers"] = frame.markers;
          line["status"] = frame.marker_status;
        }
        std::printf("%s\n", line.dump().c_str());
      }
      if (save_every > 0 && frames % save_every == 0 && !frame.positions.empty()) {
        std::vector<Vec3> vertices(info.vertex_count);
        for (uint32_t v = 0; v < info.vertex_count; ++v)
          vertices[v] = Vec3(frame.positions[3 * v], frame.positions[3 * v + 1], frame.positions[3 * v + 2]);
        char name[64];
        std::snprintf(name, sizeof name, "frame_%06u.ply", info.frame_number);
        write_ply((std::filesystem::path(save_dir) / name).string(), vertices, faces);
        ++saved;
      }
      const auto t = std::chrono::steady_clock::now();
      if (stats && !json && t - last_report >= std::chrono::seconds(1)) {
        const double seconds = std::chrono::duration<double>(t - last_report).count();
        std::printf("%.1f frames/s, %.2f MB/s total, latency since publish p50 %.2f ms, since receive p50 %.2f ms, dropped %u/%u\n",
                    (frames - frames_at_report) / seconds, bytes / 1e6 / std::chrono::duration<double>(t - start).count(),
                    since_publish.at(0.5), since_receive.at(0.5), pipeline_dropped, subscriber_dropped);
        std::fflush(stdout);
        last_report = t;
        frames_at_report = frames;
      }
      return frames_wanted <= 0 || frames < frames_wanted;
    });
    if (!refused.empty()) {
      std::fprintf(stderr, "skinstream-sub: error: the daemon refused this subscriber: %s\n", refused.c_str());
      return 1;
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    nlohmann::json summary = {{"frames", frames},
                              {"out_of_order", out_of_order},
                              {"seconds", seconds},
                              {"frames_per_second", seconds > 0 ? frames / seconds : 0.0},
                              {"megabytes", bytes / 1e6},
                              {"pipeline_dropped", pipeline_dropped},
                              {"subscriber_dropped", subscriber_dropped},
                              {"saved", saved},
                              {"latency_since_publish", since_publish.summary()},
                              {"latency_since_receive", since_receive.summary()}};
    if (!end_to_end.values.empty()) summary["latency_end_to_end"] = end_to_end.summary();
    if (json) std::printf("%s\n", nlohmann::json{{"summary", summary}}.dump().c_str());
    else std::printf("%s\n", summary.dump(2).c_str());
    if (!finished && frames_wanted > 0 && frames < frames_wanted) {
      std::fprintf(stderr, "skinstream-sub: error: the daemon closed the connection after %ld of %ld frames\n", frames, frames_wanted);
      return 1;
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "skinstream-sub: error: %s\n", e.what());
    return 1;
  }
}
