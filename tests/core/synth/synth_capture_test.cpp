#include "core/synth/synth_capture.h"

#include <gtest/gtest.h>

#include "support/rigid_residual.h"

#include <cmath>

#include "core/geometry/triangle_bvh.h"
#include "core/synth/mannequin.h"

namespace skinstream::synth {
namespace {

const Body& mannequin() {
  static const Body b = make_mannequin();
  return b;
}

SynthOptions small(const std::string& motion, double seconds, int markers = 150) {
  SynthOptions o;
  o.motion = motion;
  o.seconds = seconds;
  o.markers = markers;
  return o;
}

using test::rigid_residual;

// Over the take, RMS of the per-frame rigid residual of the chosen markers against frame 0.
double part_residual(const SynthCapture& c, const std::vector<int>& markers) {
  std::vector<Vec3> ref;
  for (int i : markers) ref.push_back(c.truth.at(0, i));
  double sum = 0.0;
  for (int f = 0; f < c.frame_count(); ++f) {
    std::vector<Vec3> now;
    for (int i : markers) now.push_back(c.truth.at(f, i));
    const double r = rigid_residual(ref, now);
    sum += r * r;
  }
  return std::sqrt(sum / c.frame_count());
}

TEST(SynthGenerate, RejectsInvalidBodyAndOptions) {
  EXPECT_THROW(generate(Body{}, small("static", 0.1)), std::invalid_argument);
  EXPECT_THROW(generate(mannequin(), small("moonwalk", 0.1)), std::invalid_argument);
  EXPECT_THROW(generate(mannequin(), small("static", 0.0)), std::invalid_argument);
  EXPECT_THROW(generate(mannequin(), small("static", -1.0)), std::invalid_argument);
  EXPECT_THROW(generate(mannequin(), small("static", std::nan(""))), std::invalid_argument);
  EXPECT_THROW(generate(mannequin(), small("static", 0.1, 5)),
               std::invalid_argument);  // fewer than the extras
  SynthOptions o = small("static", 0.1);
  o.marker_offset_mm = -1.0;
  EXPECT_THROW(generate(mannequin(), o), std::invalid_argument);
  o = small("static", 0.1);
  o.rate_hz = 0.0;
  EXPECT_THROW(generate(mannequin(), o), std::invalid_argument);
  o = small("static", 0.1);
  o.cameras = CameraRig{};
  EXPECT_THROW(generate(mannequin(), o), std::invalid_argument);
  const SynthCapture ok = generate(mannequin(), small("static", 0.1));
  EXPECT_THROW(ok.pose_mesh(-1), std::out_of_range);
  EXPECT_THROW(ok.pose_mesh(ok.frame_count()), std::out_of_range);
}

TEST(SynthGenerate, CaptureTruthAndCountsAreConsistent) {
  const SynthCapture c = generate(mannequin(), small("punch", 1.5));
  ASSERT_EQ(c.truth.point_count(), 150);
  EXPECT_EQ(c.frame_count(), 180);
  EXPECT_EQ(c.truth.rate_hz, 120.0);
  EXPECT_EQ(c.capture.frame_count, 180);
  EXPECT_EQ(summarize(c.truth).missing_fraction, 0.0);
  for (int i = 0; i < 150; ++i) {
    EXPECT_EQ(c.capture.labels[static_cast<size_t>(i)], c.truth.labels[static_cast<size_t>(i)]);
    EXPECT_EQ(c.markers[static_cast<size_t>(i)].name, c.truth.labels[static_cast<size_t>(i)]);
    EXPECT_TRUE(c.capture.present(0, i));  // the reference pose is complete
  }
  EXPECT_EQ(static_cast<int>(c.capture.labelled_points().size()), 150);
  // Unlabelled fragments and ghosts share channels (never touching), so they are the runs there.
  int runs = 0;
  for (int ch = 150; ch < c.capture.point_count(); ++ch)
    for (int f = 0; f < c.capture.frame_count; ++f) runs += c.capture.present(f, ch) && (f == 0 || !c.capture.present(f - 1, ch));
  EXPECT_EQ(runs, c.counts.unlabelled_fragments + c.counts.ghost_trajectories);
  EXPECT_LT(c.capture.point_count() - 150, runs);
  EXPECT_GT(c.counts.trajectories_before_merging, 150);
  EXPECT_GT(c.counts.holes, 0);
  const BreakCounts again = count_breaks(c.capture, c.source, 150);
  EXPECT_EQ(again.trajectories, c.counts.trajectories_before_merging);
  EXPECT_EQ(again.holes, c.counts.holes);
  // Every delivered sample of a real marker is its truth plus sub-millimetre noise.
  for (int f = 0; f < c.frame_count(); ++f)
    for (int ch = 0; ch < c.capture.point_count(); ++ch) {
      const int s = c.source[static_cast<size_t>(f) * c.capture.point_count() + ch];
      if (s >= 0) {
        ASSERT_LT((c.capture.at(f, ch) - c.truth.at(f, s)).norm(), 2.5);
      }
      if (s == -2) {
        ASSERT_FALSE(c.capture.present(f, ch));
      }
    }
}

TEST(SynthGenerate, SameSeedSameCaptureOtherSeedAnother) {
  SynthOptions o = small("jumprope", 0.75);
  o.seed = 77;
  const SynthCapture a = generate(mannequin(), o), b = generate(mannequin(), o);
  o.seed = 78;
  const SynthCapture c = generate(mannequin(), o);
  EXPECT_EQ(a.capture.labels, b.capture.labels);
  EXPECT_EQ(a.source, b.source);
  ASSERT_EQ(a.capture.positions.size(), b.capture.positions.size());
  for (size_t k = 0; k < a.capture.positions.size(); ++k)
    ASSERT_TRUE(a.capture.positions[k] == b.capture.positions[k] ||
                (!is_present(a.capture.positions[k]) && !is_present(b.capture.positions[k])));
  EXPECT_EQ(a.truth.positions, b.truth.positions);
  EXPECT_NE(a.truth.positions, c.truth.positions);  // another layout
  EXPECT_NE(a.source, c.source);
}

TEST(SynthGenerate, TruthMarkersRideOnTheTruthMeshAtTheirOffset) {
  for (bool subdivided : {false, true}) {
    SynthOptions o = small("golf", 2.5);
    o.subdivided = subdivided;
    o.marker_offset_mm = 4.0;
    const SynthCapture c = generate(mannequin(), o);
    EXPECT_EQ(c.mesh_vertex_count() > mannequin().vertex_count(), subdivided);
    for (int f : {0, 100, 200, 299}) {
      const std::vector<Vec3> mesh = c.pose_mesh(f);
      const TriangleBvh bvh(mesh, c.mesh_triangles());
      int exact = 0;
      for (int i = 0; i < c.truth.point_count(); ++i) {
        const MarkerSite& s = c.markers[static_cast<size_t>(i)];
        const Triangle& t = c.mesh_triangles()[static_cast<size_t>(s.triangle)];
        const Vec3 foot = s.barycentric[0] * mesh[static_cast<size_t>(t[0])] +
                          s.barycentric[1] * mesh[static_cast<size_t>(t[1])] +
                          s.barycentric[2] * mesh[static_cast<size_t>(t[2])];
        const Vec3 n = triangle_normal(mesh[static_cast<size_t>(t[0])], mesh[static_cast<size_t>(t[1])],
                                       mesh[static_cast<size_t>(t[2])]);
        ASSERT_LT((c.truth.at(f, i) - (foot + 4.0 * n)).norm(), 1e-9);  // on its triangle, along its normal
        const double d = bvh.closest(c.truth.at(f, i));
        ASSERT_LE(d, 4.0 + 1e-9);
        exact += std::abs(d - 4.0) < 0.1;
      }
      // Nearly all are exactly the offset from the surface; the others are near another part
      // (the mannequin's capsules overlap at the joints), closer to it than to their own.
      EXPECT_GE(exact, 0.85 * c.truth.point_count()) << "frame " << f << (subdivided ? " subdivided" : "");
    }
  }
}

TEST(SynthGenerate, BreathingAndBulgesAreNotRigid) {
  SynthOptions o = small("breathe", 5.0);
  const SynthCapture deformed = generate(mannequin(), o);
  o.deform = false;
  const SynthCapture skinned = generate(mannequin(), o);
  std::vector<int> abdomen;
  for (int i = 0; i < deformed.truth.point_count(); ++i)
    if (deformed.markers[static_cast<size_t>(i)].region == "abdomen") abdomen.push_back(i);
  ASSERT_GE(abdomen.size(), 5u);
  EXPECT_GT(part_residual(deformed, abdomen), 3.0);
  EXPECT_LT(part_residual(skinned, abdomen), 1.0);
}

}  // namespace
}  // namespace skinstream::synth
