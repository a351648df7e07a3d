#include "core/offline/subject_builder.h"

#include <gtest/gtest.h>

#include <Eigen/LU>

#include "support/synthetic_limb.h"

namespace skinstream {
namespace {

TEST(SubjectBuilder, RejectsTooFewMarkers) {
  Capture c({"a", "b", "c"}, 10, 120.0);
  for (int f = 0; f < 10; ++f)
    for (int p = 0; p < 3; ++p) c.at(f, p) = Vec3(p * 10.0, f, 0);
  EXPECT_THROW(build_subject(c, {}), std::invalid_argument);
}

TEST(SubjectBuilder, RejectsCaptureWithoutACompleteFrame) {
  Capture c = test::make_limb_capture();
  for (int f = 0; f < c.frame_count; ++f) c.at(f, f % c.point_count()) = missing_point();
  EXPECT_EQ(choose_reference_frame(c, c.labelled_points()), -1);
  EXPECT_THROW(build_subject(c, {}), std::invalid_argument);
}

TEST(SubjectBuilder, RejectsAGivenReferenceFrameWithAMissingMarker) {
  Capture c = test::make_limb_capture();
  c.at(5, 3) = missing_point();
  SubjectBuildOptions o;
  o.reference_frame = 5;
  EXPECT_THROW(build_subject(c, o), std::invalid_argument);
}

TEST(SubjectBuilder, ChoosesACompleteFrameAndBuildsAConsistentModel) {
  Capture c = test::make_limb_capture();
  c.at(0, 0) = missing_point();  // frame 0 incomplete: must not be chosen
  SubjectBuildReport report;
  const SubjectModel m = build_subject(c, {}, nullptr, &report);
  EXPECT_NE(report.reference_frame, 0);
  EXPECT_EQ(m.validate(), "");
  EXPECT_EQ(m.marker_count(), c.point_count());
  EXPECT_GE(report.mean_ring_size, 4.0);
  // Two deformation modes (bulge, twist) plus rotation noise of eq. 5: few components.
  EXPECT_LE(report.mean_pca_components, 6.0);
  EXPECT_GE(report.mean_pca_components, 1.0);
  for (int i = 0; i < m.marker_count(); ++i) {
    EXPECT_GE(m.ring_size(i), 3);
    EXPECT_NEAR(m.local_reference_frames[i].determinant(), 1.0, 1e-9);
    EXPECT_GT(m.neighbour_distance(i), 20.0);
  }
}

TEST(SubjectBuilder, PcaKeepsOnlyWhatVariesWhenTheShapeIsRigid) {
  test::LimbOptions o;
  o.bulge = 0.0;
  o.twist = 0.0;
  const SubjectModel m = build_subject(test::make_limb_capture(o), {});
  for (const MarkerPcaModel& p : m.pca) {
    EXPECT_EQ(p.variance.size(), 0) << "a rigid neighbourhood has no variance to keep";
    EXPECT_EQ(p.training_frames, o.frames);
  }
}

}  // namespace
}  // namespace skinstream
