#include "clients/skinstream/cmd_fill.h"

#include <chrono>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "protocol/files/capture_file.h"
#include "protocol/files/subject_file.h"

namespace skinstream::cli {

int run_fill(const FillOptions& o, std::FILE* out) {
  const SubjectModel model = read_subject(o.subject_path);
  const Capture input = read_capture(o.in_path);
  std::vector<MarkerStatus> status;
  CaptureFillReport report;
  const auto start = std::chrono::steady_clock::now();
  if (map_channels_to_markers(model, input) == std::vector<int>(model.marker_count(), -1))
    throw std::runtime_error(o.in_path + ": none of the subject's " + std::to_string(model.marker_count()) +
                             " marker labels is in this capture (wrong subject file?)");
  const Capture filled = fill_capture(model, input, o.fill, &status, &report);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  write_capture(filled, o.out_path);
  nlohmann::json summary = {{"input", o.in_path},
                            {"output", o.out_path},
                            {"frames", input.frame_count},
                            {"markers", model.marker_count()},
                            {"samples", {{"measured", report.measured}, {"relabelled", report.relabelled},
                                         {"filled", report.filled}, {"held", report.held}}},
                            {"rejected_labels", report.rejected_labels},
                            {"changed_measured", report.changed_measured},
                            {"unknown_labels", report.unknown_labels},
                            {"absent_markers", report.absent_markers},
                            {"latency_frames", report.latency_frames},
                            {"latency_ms", input.rate_hz > 0 ? 1000.0 * report.latency_frames / input.rate_hz : 0.0},
                            {"seconds", seconds}};
  std::fprintf(out, "%s\n", summary.dump(2).c_str());
  return 0;
}

}  // namespace skinstream::cli
