// skinstream info FILE [--json]: what a capture holds and how much of it is missing.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "clients/skinstream/commands.h"
#include "protocol/capture_file.h"

namespace skinstream::cli {

void add_info(CLI::App& app) {
  auto* cmd = app.add_subcommand("info", "Print markers, frames, rate, missing fraction and gaps of a C3D/TRC file");
  static std::string path;
  static bool json = false;
  cmd->add_option("FILE", path, "capture (.c3d or .trc)")->required();
  cmd->add_flag("--json", json, "machine-readable output");
  cmd->callback([] {
    const Capture capture = read_capture(path);
    const CaptureSummary summary = summarize(capture);
    int longest = 0;
    for (const Gap& g : summary.gaps) longest = std::max(longest, g.length);
    nlohmann::json markers = nlohmann::json::array();
    for (int p : capture.labelled_points()) {
      int missing = 0;
      for (int f = 0; f < capture.frame_count; ++f) missing += !capture.present(f, p);
      markers.push_back({{"label", capture.labels[p]},
                         {"missing_fraction", capture.frame_count ? double(missing) / capture.frame_count : 0.0}});
    }
    nlohmann::json out = {{"file", path},
                          {"labelled_markers", summary.labelled},
                          {"unlabelled_channels", summary.unlabelled},
                          {"frames", capture.frame_count},
                          {"first_frame", capture.first_frame},
                          {"rate_hz", capture.rate_hz},
                          {"duration_s", capture.rate_hz > 0 ? capture.frame_count / capture.rate_hz : 0.0},
                          {"missing_fraction", summary.missing_fraction},
                          {"gaps", summary.gaps.size()},
                          {"longest_gap_frames", longest},
                          {"markers", markers}};
    if (json) {
      std::printf("%s\n", out.dump(2).c_str());
      return;
    }
    std::printf("%s\n  %d labelled markers, %d unlabelled channels\n  %d frames at %g Hz (%.2f s), first frame %d\n"
                "  missing %.2f%% of labelled samples in %zu gaps (longest %d frames)\n",
                path.c_str(), summary.labelled, summary.unlabelled, capture.frame_count, capture.rate_hz,
                out["duration_s"].get<double>(), capture.first_frame, 100.0 * summary.missing_fraction,
                summary.gaps.size(), longest);
  });
}

}  // namespace skinstream::cli
