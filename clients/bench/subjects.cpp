#include "clients/bench/subjects.h"

#include <cctype>
#include <cstdlib>

namespace skinstream::bench {
namespace {

// The subject a daemon thread works for (-1: none, e.g. io or publish-N).
int subject_of_thread(const std::string& name, int subjects) {
  if (subjects == 1) return name == "pipeline" || name.rfind("deform-", 0) == 0 ? 0 : -1;
  for (const char* prefix : {"pipeline-", "deform-"}) {
    if (name.rfind(prefix, 0) != 0) continue;
    const std::string rest = name.substr(std::string(prefix).size());
    const int k = std::atoi(rest.c_str());
    if (!rest.empty() && std::isdigit(static_cast<unsigned char>(rest[0])) && k < subjects) return k;
  }
  return -1;
}

}  // namespace

ReplayStage replay_stage(const Capture& recording, int subjects, double spacing_mm, const std::string& single_name) {
  ReplayStage stage;
  stage.captures.reserve(static_cast<size_t>(subjects));  // the subjects point into it
  for (int k = 0; k < subjects; ++k) {
    Capture& copy = stage.captures.emplace_back(recording);
    const Vec3 offset(k * spacing_mm, 0.0, 0.0);
    for (int f = 0; f < copy.frame_count; ++f)
      for (int c = 0; c < copy.point_count(); ++c)
        if (copy.present(f, c)) copy.at(f, c) += offset;
    stage.subjects.push_back({subjects == 1 ? single_name : "Actor" + std::to_string(k + 1), &copy});
  }
  return stage;
}

std::vector<std::string> daemon_subject_arguments(const std::string& subject_file, int subjects) {
  std::vector<std::string> out;
  for (int k = 0; k < subjects; ++k)
    out.insert(out.end(), {"--subject", subjects == 1 ? subject_file : "Actor" + std::to_string(k + 1) + "=" + subject_file});
  return out;
}

std::string subscriber_subject(int index, int subjects) {
  return subjects <= 1 ? std::string() : "Actor" + std::to_string(index % subjects + 1);
}

nlohmann::json per_subject_report(int subjects, const std::map<std::string, double>& cpu_before,
                                  const std::map<std::string, double>& cpu_after, const nlohmann::json& health_before,
                                  const nlohmann::json& health_after, const std::vector<nlohmann::json>& subscribers, double seconds) {
  std::vector<double> subject_cpu(static_cast<size_t>(subjects), 0.0);
  nlohmann::json shared = nlohmann::json::object();
  for (const auto& [name, after] : cpu_after) {
    const auto before = cpu_before.find(name);
    const double used = after - (before == cpu_before.end() ? 0.0 : before->second);
    const int k = subject_of_thread(name, subjects);
    if (k >= 0) subject_cpu[static_cast<size_t>(k)] += used;
    else shared[name] = used / seconds;
  }
  nlohmann::json rows = nlohmann::json::array();
  double total = 0.0;
  for (int k = 0; k < subjects; ++k) {
    const nlohmann::json& now = health_after["subjects"][k];
    const nlohmann::json& then = health_before["subjects"][k];
    auto delta = [&](const char* key) { return now["frames"][key].get<uint64_t>() - then["frames"][key].get<uint64_t>(); };
    total += subject_cpu[static_cast<size_t>(k)];
    const uint64_t published = delta("published");
    rows.push_back({{"name", now["name"]},
                    {"cpu_share_of_one_core", subject_cpu[static_cast<size_t>(k)] / seconds},
                    // What a frame costs: less sensitive than the share to how much CPU the machine had to give.
                    {"cpu_ms_per_published_frame", published > 0 ? 1e3 * subject_cpu[static_cast<size_t>(k)] / static_cast<double>(published) : 0.0},
                    {"frames", {{"received", delta("received")}, {"published", delta("published")}, {"dropped", delta("dropped")}}},
                    {"deform", now["deform"]},
                    {"subscribers", k < static_cast<int>(subscribers.size()) ? subscribers[static_cast<size_t>(k)] : nlohmann::json()},
                    // The daemon's histograms over its whole life (warm-up included): upper bounds.
                    {"daemon_stages_ms", now["latency_ms"]}});
  }
  return {{"subjects", rows},
          {"mean_cpu_share_per_subject", subjects > 0 ? total / seconds / subjects : 0.0},
          {"shared_threads_cpu_share", shared}};
}

}  // namespace skinstream::bench
