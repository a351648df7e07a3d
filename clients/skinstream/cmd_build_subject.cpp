// skinstream build-subject: training capture -> subject model file (section 4.1-4.3).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "clients/skinstream/commands.h"
#include "core/offline/subject_builder.h"
#include "protocol/capture_file.h"
#include "protocol/marker_surface_obj.h"
#include "protocol/subject_file.h"

namespace skinstream::cli {

void add_build_subject(CLI::App& app) {
  auto* cmd = app.add_subcommand("build-subject", "Build the subject model (marker surface, local frames, PCA) from a training capture");
  static std::string capture_path, out_path, surface_in, surface_out;
  static SubjectBuildOptions options;
  cmd->add_option("--capture", capture_path, "training capture (.c3d/.trc), ideally a range-of-motion take")->required();
  cmd->add_option("--out", out_path, "subject file to write")->required();
  cmd->add_option("--reference-frame", options.reference_frame, "frame index of the reference pose (default: chosen)");
  cmd->add_option("--surface", surface_in, "marker surface OBJ to use instead of building one (vertex i = marker i)");
  cmd->add_option("--surface-out", surface_out, "also write the marker surface as OBJ");
  cmd->add_option("--variance", options.pca.variance_kept, "PCA variance kept")->check(CLI::Range(0.5, 1.0))->capture_default_str();
  cmd->add_option("--alpha1", options.parameters.alpha1, "relabel start tolerance (eq. 3)")->capture_default_str();
  cmd->add_option("--alpha2", options.parameters.alpha2, "relabel keep tolerance")->capture_default_str();
  cmd->callback([] {
    const Capture training = read_capture(capture_path);
    std::vector<std::array<int, 3>> triangles;
    if (!surface_in.empty()) triangles = read_marker_surface_obj(surface_in, static_cast<int>(training.labelled_points().size()));
    SubjectBuildReport report;
    const SubjectModel model = build_subject(training, options, surface_in.empty() ? nullptr : &triangles, &report);
    write_subject(model, out_path);
    if (!surface_out.empty())
      write_marker_surface_obj(surface_out, model.marker_names, model.reference_positions, model.triangles);
    nlohmann::json out = {{"subject", out_path},
                          {"markers", report.markers},
                          {"reference_frame", report.reference_frame},
                          {"triangles", report.triangles},
                          {"mean_ring_size", report.mean_ring_size},
                          {"markers_given_extra_neighbours", report.markers_given_extra_neighbours},
                          {"mean_pca_components", report.mean_pca_components},
                          {"min_training_frames", report.min_training_frames},
                          {"markers_never_complete", report.markers_never_complete}};
    std::printf("%s\n", out.dump(2).c_str());
  });
}

}  // namespace skinstream::cli
