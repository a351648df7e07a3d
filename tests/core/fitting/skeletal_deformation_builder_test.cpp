#include "core/fitting/skeletal_deformation_builder.h"

#include <gtest/gtest.h>

#include <random>

#include "core/deform/mesh_deformer.h"
#include "core/offline/subject_builder.h"
#include "tests/core/fitting/synthetic_actor.h"

namespace skinstream {
namespace {

struct Built {
  test::Actor actor;
  ActorFit fit;
  SubjectModel subject;
  DeformationModel model;
  SkeletalDeformationReport report;
};

Built build(uint32_t seed, int frames) {
  Built b;
  b.actor = test::make_actor(seed, frames);
  const int markers = static_cast<int>(b.actor.attachments.size());
  std::vector<std::string> labels;
  for (int i = 0; i < markers; ++i) labels.push_back("m" + std::to_string(i));
  Capture take(labels, frames, 120.0);
  take.positions = b.actor.frames;
  std::mt19937 random(seed);
  const std::vector<MarkerPrior> priors = test::guessed_priors(b.actor, random);
  b.fit = fit_actor(test::fit_body(b.actor), b.actor.frames, frames, markers, 0, priors);
  SubjectBuildOptions options;
  options.reference_frame = 0;
  b.subject = build_subject(take, options);
  b.model = build_skeletal_deformation_model(b.subject, b.fit, b.actor.triangles, b.actor.frames, frames, {}, &b.report);
  return b;
}

// The truth's skin at frame f: the actor's proportioned template posed by its true pose.
std::vector<Vec3> true_skin(const test::Actor& a, int f) {
  const std::vector<BoneMap> maps = proportion_bones(a.body.skeleton, a.segments, a.proportions);
  const std::vector<Vec3> rest = proportioned_vertices(a.body.rest, a.body.weights, maps);
  const std::vector<Vec3> pivots = proportioned_pivots(a.body.skeleton, a.segments, maps);
  SegmentSkeleton skeleton;
  for (int s = 0; s < a.segments.segment_count(); ++s)
    skeleton.segments.push_back({a.segments.segments[s].name, a.segments.segments[s].parent, pivots[s]});
  skeleton.marker_weights = {{0, 1.0}};
  skeleton.marker_weight_offsets = {0, 1};
  SkeletonSolver solver(skeleton, std::vector<Vec3>{pivots[0]});
  solver.set_pose(a.poses[f].local, a.poses[f].translation);
  std::vector<RigidTransform> motions;
  for (int s = 0; s < solver.segment_count(); ++s) motions.push_back(solver.segment_motion(s));
  return pose_vertices(rest, segment_weights(a.body.weights, a.segments), motions);
}

TEST(SkeletalDeformation, PartsAreTheSegmentsWithTheTermsTheirMarkersCarry) {
  const Built b = build(4, 120);
  EXPECT_EQ(b.model.part_count(), b.actor.segments.segment_count());
  EXPECT_EQ(b.model.validate(b.subject.marker_count()), "");
  ASSERT_EQ(b.report.parts.size(), static_cast<size_t>(b.model.part_count()));
  for (const PartChoice& part : b.report.parts) {
    // Three markers a segment in this take: never enough for eq. 6; two or more for eq. 7.
    EXPECT_FALSE(part.quadratic) << part.name;
    EXPECT_EQ(part.rbf, part.members >= 2) << part.name << ": " << part.why;
    EXPECT_FALSE(part.why.empty());
  }
  EXPECT_TRUE(b.report.registered);
  EXPECT_LT(b.report.registration.landmark_rms_after_mm, 2.0);
}

// The mesh moves as the actor's skin moves: each vertex's displacement from the reference frame,
// against the truth's, at frames of the take.
TEST(SkeletalDeformation, TheBodyMovesAsTheActorsSkin) {
  const Built b = build(5, 240);
  MeshDeformer deformer(b.model, b.subject);
  const std::vector<Vec3> truth_reference = true_skin(b.actor, 0);
  const int markers = b.subject.marker_count();
  std::vector<float> positions(3 * b.model.reference_vertices.size());
  double sum = 0.0, moved = 0.0;
  long count = 0;
  for (int f = 30; f < 240; f += 30) {
    const std::span<const Vec3> now(b.actor.frames.data() + static_cast<size_t>(f) * markers, static_cast<size_t>(markers));
    ASSERT_TRUE(deformer.deform(now, positions, {}));
    const std::vector<Vec3> truth = true_skin(b.actor, f);
    for (size_t v = 0; v < truth.size(); ++v) {
      const Vec3 mine = Vec3(positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]) - b.model.reference_vertices[v];
      const Vec3 true_move = truth[v] - truth_reference[v];
      sum += (mine - true_move).norm();
      moved += true_move.norm();
      ++count;
    }
  }
  std::printf("mean displacement error %.1f mm of a mean displacement of %.0f mm\n", sum / count, moved / count);
  EXPECT_LT(sum / count, 0.05 * moved / count);
}

}  // namespace
}  // namespace skinstream
