#include "clients/bench/bench_report.h"

#include <cstdio>
#include <string>

namespace skinstream::bench {
namespace {

void print_latency(const char* name, const nlohmann::json& s) {
  std::printf("%-20s p50 %.3f ms  p99 %.3f ms  p99.9 %.3f ms  max %.3f ms  (%zu samples)\n", name, s["p50_ms"].get<double>(),
              s["p99_ms"].get<double>(), s["p99_9_ms"].get<double>(), s["max_ms"].get<double>(), s["count"].get<size_t>());
}

}  // namespace

void print_report(const nlohmann::json& report, bool as_json) {
  if (as_json) {
    std::printf("%s\n", report.dump(2).c_str());
    return;
  }
  std::printf("%s\n", report["mode"].get<std::string>().c_str());
  const nlohmann::json& rates = report["subscriber_frames_per_second"];
  std::printf("%d subscribers (%s): slowest %.1f frames/s, median %.1f; %.0f bytes a frame\n", report["subscribers"].get<int>(),
              report["encoding"].get<std::string>().c_str(), rates["slowest"].get<double>(), rates["median"].get<double>(),
              report["bytes_per_frame"].get<double>());
  print_latency("end to end", report["end_to_end"]);
  print_latency("daemon processing", report["daemon_processing"]);
  print_latency("  ingest", report["ingest"]);
  print_latency("  delivery", report["delivery"]);
  print_latency("since receive", report["since_receive"]);
  for (const char* stage : {"subscriber_queue_wait", "subscriber_write"}) {
    const nlohmann::json& h = report["daemon_stages_ms"][stage];
    std::printf("    %-22s p50 <= %.3f ms  p99 <= %.3f ms  max %.3f ms  (daemon side, %lu samples)\n", stage, h["p50_le"].get<double>(),
                h["p99_le"].get<double>(), h["max"].get<double>(), h["count"].get<unsigned long>());
  }
  std::printf("frames: %s\n", report["frames"].dump().c_str());
  for (const auto& row : report["per_subject"]["subjects"])
    std::printf("subject %s: %.0f%% of one core, end to end p50 %.3f ms p99 %.3f ms (%ld frames to its subscribers), frames %s\n",
                row["name"].get<std::string>().c_str(), 100 * row["cpu_share_of_one_core"].get<double>(),
                row["subscribers"]["end_to_end"]["p50_ms"].get<double>(), row["subscribers"]["end_to_end"]["p99_ms"].get<double>(),
                row["subscribers"]["received"].get<long>(), row["frames"].dump().c_str());
  const nlohmann::json& d = report["daemon"];
  std::printf("daemon: %.2f s CPU (%.0f%% of one core), peak RSS %ld kB, RSS %ld kB after 1 s and %ld kB at the end\n",
              d["cpu_seconds"].get<double>(), 100 * d["cpu_share_of_one_core"].get<double>(), d["peak_rss_kb"].get<long>(),
              d["rss_kb_after_1s"].get<long>(), d["rss_kb_at_end"].get<long>());
  for (const auto& step : d["rss_steps"]) std::printf("at %.0f s: daemon RSS %+ld kB\n", step["at_s"].get<double>(), step["kb"].get<long>());
  for (const auto& text : d["warnings"]) std::printf("daemon: %s\n", text.get<std::string>().c_str());
  for (const auto& event : report["stalls"]["events"]) {
    if (event.contains("dropped"))
      std::printf("at %.3f s: %s: %u frames dropped%s\n", event["at_s"].get<double>(), event["who"].get<std::string>().c_str(),
                  event["dropped"].get<uint32_t>(), event["who"] == "pipeline" ? "" : " for it");
    else
      std::printf("at %.3f s: %s: nothing for %.1f ms\n", event["at_s"].get<double>(), event["who"].get<std::string>().c_str(),
                  event["gap_ms"].get<double>());
  }
}

}  // namespace skinstream::bench
