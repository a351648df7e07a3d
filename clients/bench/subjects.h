#pragma once
// skinstream-bench --subjects N: a stage of N actors. The replay streams the recording N times,
// each copy moved `spacing` along x and named Actor1..ActorN, and the daemon follows each by name.
// The daemon's threads are told apart by name (pipeline-K and deform-K-N belong to subject K;
// pipeline and deform-N when there is one), so each subject's CPU is the sum of its threads'
// (thread_cpu_seconds, server/client/process_usage.h).
#include <sys/types.h>

#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/capture.h"
#include "protocol/vicon/vicon_capture_encoder.h"

namespace skinstream::bench {

struct ReplayStage {
  std::vector<Capture> captures;               // one per subject
  std::vector<ReplaySubject> subjects;  // pointing into captures
};

// One subject: the recording as it is, named `single_name`; several: copies k = 0..n-1 moved
// k x spacing_mm along x, named Actor1..ActorN.
ReplayStage replay_stage(const Capture& recording, int subjects, double spacing_mm, const std::string& single_name);

// skinstreamd's --subject arguments: the file as it is for one subject, ActorK=FILE for several.
std::vector<std::string> daemon_subject_arguments(const std::string& subject_file, int subjects);

// The subject subscriber `index` follows: none named (the daemon's first) with one subject;
// Actor(index mod subjects + 1) with several, so the subscribers spread over them.
std::string subscriber_subject(int index, int subjects);

// Per subject over the window: its threads' CPU share of one core, its subscribers' figures
// (`subscribers[k]`, as measured by them) and the daemon's own figures for it (/health's subjects:
// frames and stage latencies); plus the threads no subject owns (io, publish-N) and the mean
// share a subject costs.
nlohmann::json per_subject_report(int subjects, const std::map<std::string, double>& cpu_before,
                                  const std::map<std::string, double>& cpu_after, const nlohmann::json& health_before,
                                  const nlohmann::json& health_after, const std::vector<nlohmann::json>& subscribers, double seconds);

}  // namespace skinstream::bench
