#include "core/offline/deformation_builder.h"

#include <gtest/gtest.h>

#include <array>
#include <cstdio>

#include "core/deform/mesh_deformer.h"
#include "core/geometry/triangle_mesh.h"
#include "core/offline/marker_distance_stats.h"
#include "core/offline/subject_builder.h"
#include "core/synth/mannequin.h"
#include "core/synth/synth_capture.h"

namespace skinstream {
namespace {

std::vector<Vec3> frame_markers(const Capture& truth, int frame) {
  return std::vector<Vec3>(truth.positions.begin() + static_cast<long>(frame) * truth.point_count(),
                           truth.positions.begin() + static_cast<long>(frame + 1) * truth.point_count());
}

TEST(DeformationBuilder, RejectsAnEmptyMesh) {
  SubjectModel subject;
  EXPECT_THROW(build_deformation_model(subject, {}, 0, {}, {}), std::invalid_argument);
}

// Section 5 end to end on the procedural mannequin (core tests cannot load MakeHuman): subject
// and parts from a 4 s range-of-motion take, the truth skin of the reference frame as the
// detailed model, then a 2 s flexing take of the same body deformed from its true markers.
// Measured when written, over the vertices the markers cover (mean, deterministic: seed 1):
// full method 3.163 mm, rigid parts 4.31 mm; with a hard switch at the joints' planes (no ramp)
// 3.278 mm; without the fold blend 3.199 mm; with the fold blend but not smoothed over the mesh
// 3.192 mm; with the paper's vertex weights alone (no split at the parts' joints, no blend
// across folds) 3.37 mm. The mannequin is not the MakeHuman body the joint criteria, the ramp,
// the fold blend and its smoothing were measured on, so those comparisons are checks on another
// body. One addition loses here and is not asserted: the marker weights' boundary a ring wider
// (MarkerWeightOptions::boundary_rings) gives 3.192 against the paper's 3.180 mm (measured before
// the fold smoothing), where the MakeHuman body's mean falls in 22 of 25 takes. Every vertex
// weight sums to 1 and the reference pose reproduces the mesh.
TEST(DeformationBuilder, DeformedFramesMatchTheSyntheticTruth) {
  const Body body = synth::make_mannequin();
  synth::SynthOptions rom;
  rom.motion = "rom";
  rom.seconds = 4.0;
  const synth::SynthCapture training = synth::generate(body, rom);
  SubjectBuildReport report;
  const SubjectModel subject = build_subject(training.truth, {}, nullptr, &report);
  ASSERT_EQ(subject.marker_names, training.truth.labels);  // same order: truth channels = markers
  DeformationBuildOptions options;
  options.register_mesh = false;
  // The mannequin's truth skin of the reference frame, built into a model under `options`.
  const std::vector<Vec3> reference_skin = training.pose_mesh(report.reference_frame, true);
  auto build = [&](DeformationBuildReport* report_out = nullptr) {
    return build_deformation_model(subject, training.truth.positions, training.frame_count(), reference_skin,
                                   training.mesh_triangles(), options, report_out);
  };
  DeformationBuildReport built;
  const DeformationModel model = build(&built);
  EXPECT_EQ(built.joints.size(), 4u);  // the elbows and the knees
  EXPECT_GT(built.joint_blend_mm, 0.0);
  EXPECT_GT(built.fold_smoothed_vertices, 0);
  EXPECT_DOUBLE_EQ(built.joint_blend_mm, 0.5 * median_nearest_marker_distance(subject.reference_positions));
  options.blend_at_joints = false;
  const DeformationModel hard_split = build();
  options.blend_at_joints = true;
  options.smooth_folds = false;
  const DeformationModel unsmoothed = build();
  options.smooth_folds = true;
  options.blend_folds = false;
  const DeformationModel unfolded = build();
  options.split_at_joints = false;  // and no fold blend: the paper's nearest triangle alone
  const DeformationModel paper_weights = build();
  EXPECT_EQ(model.validate(subject.marker_count()), "");
  EXPECT_EQ(model.part_count(), 17);
  ASSERT_EQ(model.part_rbf_ridge.size(), 17u);  // one per part, chosen by leave-one-out error
  ASSERT_EQ(model.part_quadratic_ridge.size(), 17u);  // likewise, eq. 6's
  for (int v = 0; v < model.vertex_count(); ++v) {
    double sum = 0.0;
    for (int k = model.vertex_influence_offsets[v]; k < model.vertex_influence_offsets[v + 1]; ++k)
      sum += model.vertex_influences[k].weight;
    ASSERT_NEAR(sum, 1.0, 1e-9) << v;
  }

  std::vector<float> positions(static_cast<size_t>(model.vertex_count()) * 3);
  MeshDeformer full(model, subject, DeformationMode::QuadraticRbf), rigid(model, subject, DeformationMode::Rigid);
  MeshDeformer unsplit(paper_weights, subject, DeformationMode::QuadraticRbf);
  MeshDeformer no_folds(unfolded, subject, DeformationMode::QuadraticRbf);
  MeshDeformer hard(hard_split, subject, DeformationMode::QuadraticRbf);
  MeshDeformer fold_blend_only(unsmoothed, subject, DeformationMode::QuadraticRbf);
  // The reference frame's own markers give back the reference mesh.
  ASSERT_TRUE(full.deform(frame_markers(training.truth, report.reference_frame), positions, {}));
  double rest_error = 0.0;
  for (int v = 0; v < model.vertex_count(); ++v)
    rest_error = std::max(rest_error, (Vec3(positions[v * 3], positions[v * 3 + 1], positions[v * 3 + 2]) -
                                       model.reference_vertices[v]).norm());
  EXPECT_LT(rest_error, 0.05);

  synth::SynthOptions flex = rom;
  flex.motion = "flex";
  flex.seconds = 2.0;
  const synth::SynthCapture take = synth::generate(body, flex);
  // Vertices the markers cover (within 30 mm of the reference marker surface; the head, hands
  // and feet carry no markers), as eval-deform reports them.
  std::vector<char> covered(model.vertex_count(), 0);
  long covered_count = 0;
  for (int v = 0; v < model.vertex_count(); ++v)
    for (const auto& t : subject.triangles) {
      const Vec3 q = closest_point_on_triangle(model.reference_vertices[v], subject.reference_positions[t[0]],
                                                      subject.reference_positions[t[1]], subject.reference_positions[t[2]]);
      if ((q - model.reference_vertices[v]).norm() <= 30.0) {
        covered[v] = 1;
        ++covered_count;
        break;
      }
    }
  ASSERT_GT(covered_count, model.vertex_count() / 5);
  struct Tally {
    MeshDeformer* deformer;
    double sum = 0.0, max = 0.0;
  };
  std::array<Tally, 6> tallies{{{&full}, {&rigid}, {&unsplit}, {&no_folds}, {&hard}, {&fold_blend_only}}};
  long count = 0;
  for (int f = 0; f < take.frame_count(); f += 12) {
    const std::vector<Vec3> truth = take.pose_mesh(f);
    const std::vector<Vec3> markers = frame_markers(take.truth, f);
    for (Tally& t : tallies) {
      ASSERT_TRUE(t.deformer->deform(markers, positions, {}));
      for (int v = 0; v < model.vertex_count(); ++v)
        if (covered[v]) {
          const double e = (Vec3(positions[v * 3], positions[v * 3 + 1], positions[v * 3 + 2]) - truth[v]).norm();
          t.sum += e;
          t.max = std::max(t.max, e);
        }
    }
    count += covered_count;
  }
  const double full_mean = tallies[0].sum / count, rigid_mean = tallies[1].sum / count,
               unsplit_mean = tallies[2].sum / count, unfolded_mean = tallies[3].sum / count,
               hard_mean = tallies[4].sum / count, unsmoothed_mean = tallies[5].sum / count;
  std::printf("deformation builder: mean (max) vertex error: full %.3f (%.1f) mm, rigid %.3f (%.1f), the paper's vertex "
              "weights %.3f (%.1f), without the fold blend %.3f (%.1f), a hard switch at joints %.3f (%.1f), the fold blend "
              "unsmoothed %.3f (%.1f)\n",
              full_mean, tallies[0].max, rigid_mean, tallies[1].max, unsplit_mean, tallies[2].max, unfolded_mean, tallies[3].max,
              hard_mean, tallies[4].max, unsmoothed_mean, tallies[5].max);
  EXPECT_LT(full_mean, 4.0);
  EXPECT_LT(full_mean, rigid_mean);
  EXPECT_LT(full_mean, unsplit_mean);
  EXPECT_LT(full_mean, unfolded_mean);
  EXPECT_LT(full_mean, hard_mean);
  EXPECT_LT(full_mean, unsmoothed_mean);
}

}  // namespace
}  // namespace skinstream
