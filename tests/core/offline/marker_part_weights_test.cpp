#include "core/offline/marker_part_weights.h"

#include <gtest/gtest.h>

#include <limits>

#include "core/offline/part_segmentation.h"
#include "tests/core/offline/offline_test_support.h"

namespace skinstream {
namespace {

using test::ArticulatedLimb;
using test::make_articulated_limb;

constexpr int kMarkerWeightFrames = 240;

// The limb cut by its segments: a triangle spanning a joint goes with two of its markers, so the
// last ring before a joint and the first after it are the boundary markers.
struct MarkerWeightsFixture {
  ArticulatedLimb limb = make_articulated_limb(3, kMarkerWeightFrames);
  std::vector<int> triangle_part =
      segmentation_from_assignment(limb.reference, limb.triangles, limb.positions, kMarkerWeightFrames, limb.segment, AssignmentKind::PerMarker)
          .triangle_part;
};

std::vector<double> row_sums(const MarkerPartWeights& w, int markers) {
  std::vector<double> sum(markers, 0.0);
  for (const PartMember& m : w.part_members) sum[m.marker] += m.weight;
  return sum;
}

TEST(MarkerPartWeights, RejectsBadInputs) {
  const MarkerWeightsFixture f;
  const auto& l = f.limb;
  EXPECT_THROW(marker_part_weights(l.reference, l.triangles, std::vector<int>(3, 0), 3, l.positions, kMarkerWeightFrames), std::invalid_argument);
  std::vector<int> out_of_range = f.triangle_part;
  out_of_range[5] = 3;
  EXPECT_THROW(marker_part_weights(l.reference, l.triangles, out_of_range, 3, l.positions, kMarkerWeightFrames), std::invalid_argument);
  EXPECT_THROW(marker_part_weights(l.reference, l.triangles, f.triangle_part, 4, l.positions, kMarkerWeightFrames),
               std::invalid_argument);  // part 3 has no triangle
  EXPECT_THROW(marker_part_weights(l.reference, l.triangles, f.triangle_part, 3, l.positions, kMarkerWeightFrames - 1), std::invalid_argument);
  auto nan = l.positions;
  nan[100].y() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(marker_part_weights(l.reference, l.triangles, f.triangle_part, 3, nan, kMarkerWeightFrames), std::invalid_argument);
  MarkerWeightOptions o;
  o.threshold = 1.0;
  EXPECT_THROW(marker_part_weights(l.reference, l.triangles, f.triangle_part, 3, l.positions, kMarkerWeightFrames, o), std::invalid_argument);
  MarkerWeightOptions rings;
  rings.boundary_rings = -1;
  EXPECT_THROW(marker_part_weights(l.reference, l.triangles, f.triangle_part, 3, l.positions, kMarkerWeightFrames, rings),
               std::invalid_argument);
}

// With the paper's boundary (no rings added).
TEST(MarkerPartWeights, InsideMarkersWeighOneAndBoundaryMarkersFollowTheirSegment) {
  const MarkerWeightsFixture f;
  const auto& l = f.limb;
  const int m = static_cast<int>(l.reference.size());
  MarkerWeightOptions paper;
  paper.boundary_rings = 0;
  const MarkerPartWeights w = marker_part_weights(l.reference, l.triangles, f.triangle_part, 3, l.positions, kMarkerWeightFrames, paper);
  ASSERT_EQ(w.part_member_offsets.size(), 4u);
  for (double s : row_sums(w, m)) EXPECT_NEAR(s, 1.0, 1e-12);
  EXPECT_EQ(w.boundary_markers, 4 * l.around);  // the rings on either side of the two joints
  EXPECT_EQ(w.markers_added_for_min_members, 0);
  for (int ring = 0; ring < 12; ++ring)
    for (int a = 0; a < l.around; ++a) {
      const int i = l.marker(ring, a);
      const int seg = l.segment[i];
      const bool boundary = ring == 3 || ring == 4 || ring == 7 || ring == 8;
      if (!boundary) {
        EXPECT_EQ(w.weight(i, seg), 1.0) << "inside marker " << i;  // exactly
      } else {
        // Moves exactly with its own segment: (almost) all of its weight goes there.
        EXPECT_GT(w.weight(i, seg), 0.999) << "boundary marker " << i;
      }
    }
  for (int p = 0; p < 3; ++p) EXPECT_EQ(w.part_sigma_mm[p], 1.0);  // rigid parts: the floor
  // Deterministic.
  const MarkerPartWeights again =
      marker_part_weights(l.reference, l.triangles, f.triangle_part, 3, l.positions, kMarkerWeightFrames, paper);
  ASSERT_EQ(again.part_members.size(), w.part_members.size());
  for (size_t k = 0; k < w.part_members.size(); ++k) EXPECT_EQ(again.part_members[k].weight, w.part_members[k].weight);
}

// A boundary marker moving halfway between its two parts gets half of each; a threshold above
// one half keeps only the stronger (then weight 1).
TEST(MarkerPartWeights, SplitsAMarkerBetweenPartsAndRespectsTheThreshold) {
  MarkerWeightsFixture f;
  auto& l = f.limb;
  const int m = static_cast<int>(l.reference.size());
  const int i = l.marker(3, 2);  // last ring of segment 0, boundary of parts 0 and 1
  test::move_halfway(l, i, 5, kMarkerWeightFrames);  // segment 1's ring 5
  const MarkerPartWeights w = marker_part_weights(l.reference, l.triangles, f.triangle_part, 3, l.positions, kMarkerWeightFrames);
  for (double s : row_sums(w, m)) EXPECT_NEAR(s, 1.0, 1e-12);
  EXPECT_NEAR(w.weight(i, 0), 0.5, 1e-6);
  EXPECT_NEAR(w.weight(i, 1), 0.5, 1e-6);
  for (const PartMember& member : w.part_members) EXPECT_GT(member.weight, 0.2);

  MarkerWeightOptions strict;
  strict.threshold = 0.6;
  const MarkerPartWeights one = marker_part_weights(l.reference, l.triangles, f.triangle_part, 3, l.positions, kMarkerWeightFrames, strict);
  EXPECT_EQ(one.weight(i, 0) + one.weight(i, 1), 1.0);
  EXPECT_TRUE(one.weight(i, 0) == 0.0 || one.weight(i, 1) == 0.0);
  for (double s : row_sums(one, m)) EXPECT_NEAR(s, 1.0, 1e-12);
}

// A marker one ring in from a seam is inside its part by the paper's rule (weight 1 whatever it
// does) but weighed by likelihood with one ring added: moving wholly with the part across the
// seam, it follows that part. Each ring widens the boundary band by a ring of the limb either side.
TEST(MarkerPartWeights, AMarkerARingInFromASeamIsWeighedToo) {
  MarkerWeightsFixture f;
  auto& l = f.limb;
  const int m = static_cast<int>(l.reference.size());
  const int i = l.marker(2, 5);  // segment 0; ring 3 is the seam with segment 1
  test::move_with_ring(l, i, 5, kMarkerWeightFrames, 1.0);
  MarkerWeightOptions o;
  o.boundary_rings = 0;
  const MarkerPartWeights paper = marker_part_weights(l.reference, l.triangles, f.triangle_part, 3, l.positions, kMarkerWeightFrames, o);
  EXPECT_EQ(paper.weight(i, 0), 1.0);
  EXPECT_EQ(paper.boundary_markers, 4 * l.around);  // rings 3-4 and 7-8
  o.boundary_rings = 1;
  const MarkerPartWeights one = marker_part_weights(l.reference, l.triangles, f.triangle_part, 3, l.positions, kMarkerWeightFrames, o);
  EXPECT_GT(one.weight(i, 1), 0.99);
  EXPECT_EQ(one.weight(i, 0), 0.0);  // under the threshold
  EXPECT_EQ(one.boundary_markers, 8 * l.around);  // rings 2-9
  for (double s : row_sums(one, m)) EXPECT_NEAR(s, 1.0, 1e-12);
  // Its neighbours still move with segment 0 and stay there.
  EXPECT_GT(one.weight(l.marker(2, 4), 0), 0.99);
  EXPECT_GT(one.weight(l.marker(1, 5), 0), 0.99);
  o.boundary_rings = 2;
  const MarkerPartWeights two = marker_part_weights(l.reference, l.triangles, f.triangle_part, 3, l.positions, kMarkerWeightFrames, o);
  EXPECT_EQ(two.boundary_markers, 10 * l.around);  // rings 1-10: the end rings are two rings from any seam
  EXPECT_EQ(two.weight(l.marker(0, 0), 0), 1.0);
}

// A part of a single triangle has 3 markers: a fourth (the nearest) is added. (With the
// paper's boundary: a ring added would weigh the triangle's 9 neighbours against it as well.)
TEST(MarkerPartWeights, EveryPartKeepsFourMembers) {
  const MarkerWeightsFixture f;
  const auto& l = f.limb;
  const int m = static_cast<int>(l.reference.size());
  std::vector<int> parts(l.triangles.size(), 0);
  parts[20] = 1;
  MarkerWeightOptions paper;
  paper.boundary_rings = 0;
  const MarkerPartWeights w = marker_part_weights(l.reference, l.triangles, parts, 2, l.positions, kMarkerWeightFrames, paper);
  EXPECT_EQ(w.part_member_offsets[2] - w.part_member_offsets[1], 4);
  EXPECT_EQ(w.markers_added_for_min_members, 1);
  for (double s : row_sums(w, m)) EXPECT_NEAR(s, 1.0, 1e-12);
  for (const PartMember& member : w.part_members) EXPECT_GT(member.weight, 0.0);
}

}  // namespace
}  // namespace skinstream
