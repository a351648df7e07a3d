// skinstream fill: run the online gap filler over a capture, exactly as the daemon would.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <map>
#include <nlohmann/json.hpp>

#include "clients/skinstream/commands.h"
#include "core/capture_filler.h"
#include "protocol/capture_file.h"
#include "protocol/subject_file.h"

namespace skinstream::cli {

void add_fill(CLI::App& app) {
  auto* cmd = app.add_subcommand("fill", "Relabel and fill gaps online (causal by default) and write the filled capture");
  static std::string subject_path, in_path, out_path, smoothing = "none";
  static CaptureFillOptions options;
  cmd->add_option("--subject", subject_path, "subject file from build-subject")->required();
  cmd->add_option("IN", in_path, "capture with gaps")->required();
  cmd->add_option("--out", out_path, "filled capture to write")->required();
  cmd->add_option("--lookahead", options.lookahead, "frames of lookahead: the gap-end blend, and new relabels confirmed over them (0 = causal)")
      ->check(CLI::Range(0, 240))->capture_default_str();
  cmd->add_option("--smooth", smoothing, "local-frame smoothing: none, online (adds its lookahead), offline")
      ->check(CLI::IsMember({"none", "online", "offline"}))->capture_default_str();
  cmd->add_option("--smooth-lookahead", options.smoothing_options.lookahead, "online smoothing lookahead frames")->capture_default_str();
  cmd->add_option("--continuity-seconds", options.filler.continuity_seconds, "gap-start continuity decay (0 = off)")->capture_default_str();
  cmd->add_flag("!--no-pca", options.filler.use_pca, "use only the rigid neighbour estimate (eq. 2)");
  cmd->callback([] {
    const SubjectModel model = read_subject(subject_path);
    const Capture input = read_capture(in_path);
    options.smoothing = smoothing == "online" ? SmoothingMode::Online : smoothing == "offline" ? SmoothingMode::Offline : SmoothingMode::None;
    std::vector<MarkerStatus> status;
    CaptureFillReport report;
    const auto start = std::chrono::steady_clock::now();
    if (map_channels_to_markers(model, input) == std::vector<int>(model.marker_count(), -1))
      throw std::runtime_error(in_path + ": none of the subject's " + std::to_string(model.marker_count()) +
                               " marker labels is in this capture (wrong subject file?)");
    const Capture filled = fill_capture(model, input, options, &status, &report);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    write_capture(filled, out_path);
    nlohmann::json out = {{"input", in_path},
                          {"output", out_path},
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
    std::printf("%s\n", out.dump(2).c_str());
  });
}

}  // namespace skinstream::cli
