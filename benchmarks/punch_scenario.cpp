#include "benchmarks/punch_scenario.h"

#include "core/offline/deformation_builder.h"
#include "core/offline/subject_builder.h"
#include "core/synth/synth_capture.h"
#include "protocol/offline/makehuman.h"

namespace skinstream {

const Scenario& scenario() {
  static const Scenario s = [] {
    const Body body = load_makehuman(std::string(SKINSTREAM_SHARED_DIR) + "/data/meshes/makehuman");
    synth::SynthOptions rom;
    rom.motion = "rom";
    rom.seconds = 10.0;
    rom.subdivided = true;
    const synth::SynthCapture training = synth::generate(body, rom);
    Scenario out;
    SubjectBuildReport report;
    out.subject = build_subject(training.truth, {}, nullptr, &report);
    const int n = out.subject.marker_count();
    std::vector<Vec3> positions(static_cast<size_t>(training.frame_count()) * n);
    for (int f = 0; f < training.frame_count(); ++f)
      for (int i = 0; i < n; ++i) positions[static_cast<size_t>(f) * n + i] = training.truth.at(f, i);
    DeformationBuildOptions options;
    options.register_mesh = false;  // speed of the runtime only: the truth skin is registered already
    out.model = build_deformation_model(out.subject, positions, training.frame_count(),
                                        training.pose_mesh(report.reference_frame, true), training.mesh_triangles(), options);
    synth::SynthOptions punch = rom;
    punch.motion = "punch";
    punch.seconds = 5.0;
    const synth::SynthCapture take = synth::generate(body, punch);
    for (int f = 0; f < take.frame_count(); ++f) {
      std::vector<Vec3> markers(n);
      for (int i = 0; i < n; ++i) markers[i] = take.truth.at(f, i);
      out.frames.push_back(std::move(markers));
    }
    return out;
  }();
  return s;
}

}  // namespace skinstream
