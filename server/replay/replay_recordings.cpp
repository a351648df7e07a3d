#include "server/replay/replay_recordings.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <stdexcept>

#include "protocol/files/capture_file.h"
#include "protocol/files/file_error.h"

namespace skinstream::server {

ReplayRecordings load_replay_recordings(const std::vector<std::string>& paths, const std::vector<std::string>& subject_names,
                                        double rate) {
  if (paths.empty()) throw std::invalid_argument("no recording given");
  if (!subject_names.empty() && subject_names.size() != paths.size())
    throw std::invalid_argument("--subject is given " + std::to_string(subject_names.size()) + " times for " +
                                std::to_string(paths.size()) + " recordings: once per recording, or not at all");
  for (size_t i = 0; i < subject_names.size(); ++i)
    if (std::count(subject_names.begin(), subject_names.begin() + static_cast<long>(i), subject_names[i]) > 0)
      throw std::invalid_argument("two recordings stream as subject \"" + subject_names[i] + "\": name each once");
  ReplayRecordings out;
  for (const std::string& path : paths) {
    auto capture = std::make_unique<Capture>(read_capture(path));
    if (capture->frame_count <= 0) throw FileError(path, "holds no frames");
    if (!(capture->rate_hz > 0.0) && !(rate > 0.0)) throw FileError(path, "has no frame rate; pass --rate");
    if (!(rate > 0.0) && !out.captures.empty() && std::abs(capture->rate_hz - out.captures[0]->rate_hz) > 1e-9)
      throw std::invalid_argument(path + " is at " + std::to_string(capture->rate_hz) + " Hz, " + paths[0] + " at " +
                                  std::to_string(out.captures[0]->rate_hz) + " Hz; pass --rate to stream both");
    std::string name = subject_names.empty() ? std::filesystem::path(path).stem().string() : subject_names[out.subjects.size()];
    const std::string base = name;
    for (int n = 2; std::any_of(out.subjects.begin(), out.subjects.end(), [&](const auto& s) { return s.name == name; });
         ++n)
      name = base + "_" + std::to_string(n);
    out.subjects.push_back({name, capture.get()});
    out.captures.push_back(std::move(capture));
  }
  out.rate_hz = rate > 0.0 ? rate : out.captures[0]->rate_hz;
  return out;
}

}  // namespace skinstream::server
