#include "clients/skinstream/cmd_info.h"

#include <algorithm>
#include <nlohmann/json.hpp>

#include "protocol/files/capture_file.h"

namespace skinstream::cli {

int run_info(const InfoOptions& o, std::FILE* out) {
  const Capture capture = read_capture(o.path);
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
  nlohmann::json report = {{"file", o.path},
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
  if (o.json) {
    std::fprintf(out, "%s\n", report.dump(2).c_str());
    return 0;
  }
  std::fprintf(out,
               "%s\n  %d labelled markers, %d unlabelled channels\n  %d frames at %g Hz (%.2f s), first frame %d\n"
               "  missing %.2f%% of labelled samples in %zu gaps (longest %d frames)\n",
               o.path.c_str(), summary.labelled, summary.unlabelled, capture.frame_count, capture.rate_hz,
               report["duration_s"].get<double>(), capture.first_frame, 100.0 * summary.missing_fraction,
               summary.gaps.size(), longest);
  return 0;
}

}  // namespace skinstream::cli
