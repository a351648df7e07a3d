#include "core/offline/part_segmentation.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <map>
#include <set>

#include "core/offline/subject_builder.h"
#include "core/synth/mannequin.h"
#include "core/synth/synth_capture.h"
#include "tests/core/offline/offline_test_support.h"

namespace skinstream {
namespace {

using test::ArticulatedLimb;
using test::make_articulated_limb;

// Connected through shared markers, within each part.
bool parts_connected(const std::vector<std::array<int, 3>>& triangles, const PartSegmentation& s) {
  for (int p = 0; p < s.part_count; ++p) {
    std::vector<int> tris;
    for (size_t t = 0; t < triangles.size(); ++t)
      if (s.triangle_part[t] == p) tris.push_back(static_cast<int>(t));
    if (tris.empty()) return false;
    std::set<int> reached{tris[0]};
    std::set<int> markers(triangles[tris[0]].begin(), triangles[tris[0]].end());
    for (bool grew = true; grew;) {
      grew = false;
      for (int t : tris)
        if (!reached.count(t) && std::any_of(triangles[t].begin(), triangles[t].end(), [&](int v) { return markers.count(v); })) {
          reached.insert(t);
          markers.insert(triangles[t].begin(), triangles[t].end());
          grew = true;
        }
    }
    if (reached.size() != tris.size()) return false;
  }
  return true;
}

// The limb's three segments asked for as three parts.
PartSegmentation segment_limb_in_three(const ArticulatedLimb& limb, int frames) {
  SegmentationOptions o;
  o.target_parts = 3;
  return segment_parts(limb.reference, limb.triangles, limb.positions, frames, o);
}

TEST(PartSegmentation, RejectsBadInputs) {
  const ArticulatedLimb limb = make_articulated_limb(3, 20);
  const int frames = 20;
  EXPECT_THROW(segment_parts(limb.reference, {}, limb.positions, frames), std::invalid_argument);
  EXPECT_THROW(segment_parts(limb.reference, limb.triangles, limb.positions, frames + 1), std::invalid_argument);
  auto bad = limb.triangles;
  bad[2][0] = static_cast<int>(limb.reference.size());
  EXPECT_THROW(segment_parts(limb.reference, bad, limb.positions, frames), std::invalid_argument);
  auto nan = limb.positions;
  nan[17].x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(segment_parts(limb.reference, limb.triangles, nan, frames), std::invalid_argument);
  SegmentationOptions o;
  o.target_parts = 0;
  EXPECT_THROW(segment_parts(limb.reference, limb.triangles, limb.positions, frames, o), std::invalid_argument);
  const std::vector<int> short_list(3, 0), negative(limb.triangles.size(), -1);
  EXPECT_THROW(segmentation_from_assignment(limb.reference, limb.triangles, limb.positions, frames, short_list,
                                            AssignmentKind::PerTriangle),
               std::invalid_argument);
  EXPECT_THROW(segmentation_from_assignment(limb.reference, limb.triangles, limb.positions, frames, negative,
                                            AssignmentKind::PerTriangle),
               std::invalid_argument);
}

// Three rigid segments bending at two joints: the three parts are the segments. A triangle
// spanning a joint may go either way; every triangle of one segment goes with it.
TEST(PartSegmentation, FindsTheSegmentsOfAnArticulatedLimb) {
  const int frames = 240;
  const ArticulatedLimb limb = make_articulated_limb(3, frames);
  const PartSegmentation s = segment_limb_in_three(limb, frames);
  ASSERT_EQ(s.part_count, 3);
  ASSERT_EQ(s.triangle_part.size(), limb.triangles.size());
  EXPECT_TRUE(parts_connected(limb.triangles, s));
  std::map<int, int> part_of_segment;
  for (size_t t = 0; t < limb.triangles.size(); ++t) {
    const auto& tri = limb.triangles[t];
    const int seg = limb.segment[tri[0]];
    if (limb.segment[tri[1]] != seg || limb.segment[tri[2]] != seg) continue;  // spans a joint
    const auto [it, inserted] = part_of_segment.emplace(seg, s.triangle_part[t]);
    EXPECT_EQ(it->second, s.triangle_part[t]) << "triangle " << t << " of segment " << seg;
  }
  ASSERT_EQ(part_of_segment.size(), 3u);
  EXPECT_NE(part_of_segment[0], part_of_segment[1]);
  EXPECT_NE(part_of_segment[1], part_of_segment[2]);
  EXPECT_NE(part_of_segment[0], part_of_segment[2]);
  // The triangles spanning a joint bring a ring of the next segment: measured 7.6, 11.4 and
  // 8.4 mm per part, against 33 mm for the limb fitted as one body.
  const PartSegmentation whole = segmentation_from_assignment(limb.reference, limb.triangles, limb.positions, frames,
                                                              std::vector<int>(limb.triangles.size(), 0),
                                                              AssignmentKind::PerTriangle);
  for (double rms : s.part_rigid_rms_mm) EXPECT_LT(rms, 0.4 * whole.part_rigid_rms_mm[0]);
  EXPECT_GE(s.connected_groups, 3);

  // Deterministic.
  const PartSegmentation again = segment_limb_in_three(limb, frames);
  EXPECT_EQ(again.triangle_part, s.triangle_part);
  EXPECT_EQ(again.part_rigid_rms_mm, s.part_rigid_rms_mm);

  // A user's segmentation per marker: the segments themselves.
  const PartSegmentation user = segmentation_from_assignment(limb.reference, limb.triangles, limb.positions, frames,
                                                             limb.segment, AssignmentKind::PerMarker);
  ASSERT_EQ(user.part_count, 3);
  for (size_t t = 0; t < limb.triangles.size(); ++t) {
    const auto& tri = limb.triangles[t];
    if (limb.segment[tri[0]] == limb.segment[tri[1]] && limb.segment[tri[1]] == limb.segment[tri[2]]) {
      EXPECT_EQ(user.triangle_part[t], limb.segment[tri[0]]);
    }
  }
  for (double rms : user.part_rigid_rms_mm) EXPECT_LT(rms, 0.4 * whole.part_rigid_rms_mm[0]);
}

// The dense synthetic body (procedural mannequin, 350 markers, 4 s range of motion, seed 1):
// 17 connected parts with a low within-part rigid residual, and the forearm and upper-arm
// markers of a side fall in different parts. Measured (572 triangles, 78 mean-shift groups):
// within-part rigid RMS 9.4 mm on average, worst part 20 mm (a shoulder strip), against 125 mm
// for the body fitted as one rigid part; the mannequin's
// skin weights blend widely and its skin bulges and jiggles, so no part is truly rigid.
TEST(PartSegmentation, SegmentsTheSyntheticRangeOfMotionTake) {
  synth::SynthOptions options;
  options.motion = "rom";
  options.seconds = 4.0;
  options.seed = 1;
  const synth::SynthCapture take = synth::generate(synth::make_mannequin(), options);
  const SubjectModel subject = build_subject(take.truth, {});
  const int frames = take.truth.frame_count;
  const PartSegmentation s = segment_parts(subject.reference_positions, subject.triangles, take.truth.positions, frames);
  ASSERT_EQ(s.part_count, 17);
  EXPECT_TRUE(parts_connected(subject.triangles, s));
  double mean = 0.0, worst = 0.0;
  for (double rms : s.part_rigid_rms_mm) {
    mean += rms / s.part_count;
    worst = std::max(worst, rms);
  }
  EXPECT_LT(mean, 12.0);
  EXPECT_LT(worst, 25.0);
  const PartSegmentation whole = segmentation_from_assignment(subject.reference_positions, subject.triangles, take.truth.positions,
                                                              frames, std::vector<int>(subject.triangles.size(), 0),
                                                              AssignmentKind::PerTriangle);
  EXPECT_GT(whole.part_rigid_rms_mm[0], 4.0 * mean);

  // Parts holding each region's markers (a marker counts for a part when a triangle of it is).
  std::map<std::string, std::set<int>> parts_of_region;
  for (size_t t = 0; t < subject.triangles.size(); ++t)
    for (int v : subject.triangles[t]) parts_of_region[take.markers[v].region].insert(s.triangle_part[t]);
  for (const char* side : {"_L", "_R"}) {
    // Every pair of a forearm and an upper-arm marker sits in different parts, apart from the
    // triangles that bridge the elbow: so the two regions' main parts differ.
    auto main_part = [&](const std::string& region) {
      std::map<int, int> count;
      for (size_t t = 0; t < subject.triangles.size(); ++t)
        for (int v : subject.triangles[t])
          if (take.markers[v].region == region) ++count[s.triangle_part[t]];
      int best = -1;
      for (const auto& [p, c] : count)
        if (best < 0 || c > count[best]) best = p;
      return best;
    };
    EXPECT_NE(main_part(std::string("forearm") + side), main_part(std::string("upperarm") + side)) << side;
    EXPECT_NE(main_part(std::string("forearm") + side), main_part("abdomen")) << side;
  }
}

// A segmentation written per marker (marker_parts) reads back as the same parts: the form of
// `build-subject --part-file-out`, which a user adjusts by hand and gives to --part-file.
TEST(PartSegmentation, MarkerPartsReadBackAsTheSameParts) {
  const int frames = 240;
  const ArticulatedLimb limb = make_articulated_limb(3, frames);
  const PartSegmentation s = segment_limb_in_three(limb, frames);
  const int markers = static_cast<int>(limb.reference.size());
  const std::vector<int> per_marker = marker_parts(limb.triangles, s.triangle_part, markers);
  ASSERT_EQ(per_marker.size(), limb.reference.size());
  for (int m = 0; m < markers; ++m) {
    // The part holding most of the marker's triangles.
    std::map<int, int> count;
    for (size_t t = 0; t < limb.triangles.size(); ++t)
      for (int v : limb.triangles[t])
        if (v == m) ++count[s.triangle_part[t]];
    int most = 0;
    for (const auto& [part, n] : count) most = std::max(most, n);
    ASSERT_GT(most, 0) << "marker " << m << " is in no triangle";
    EXPECT_EQ(count[per_marker[m]], most) << "marker " << m;
  }
  const PartSegmentation back = segmentation_from_assignment(limb.reference, limb.triangles, limb.positions, frames,
                                                             per_marker, AssignmentKind::PerMarker);
  ASSERT_EQ(back.part_count, s.part_count);
  EXPECT_TRUE(back.unused_parts.empty());
  // Only triangles between parts can change: one whose three markers share a main part keeps it.
  int changed = 0;
  for (size_t t = 0; t < limb.triangles.size(); ++t) {
    const auto& tri = limb.triangles[t];
    changed += back.triangle_part[t] != s.triangle_part[t];
    if (per_marker[tri[0]] != per_marker[tri[1]] || per_marker[tri[1]] != per_marker[tri[2]]) continue;
    EXPECT_EQ(back.triangle_part[t], s.triangle_part[t]) << "triangle " << t;
  }
  EXPECT_LE(changed, static_cast<int>(limb.triangles.size()) / 20);
  EXPECT_THROW(marker_parts(limb.triangles, std::vector<int>(3, 0), markers), std::invalid_argument);
  EXPECT_THROW(marker_parts(limb.triangles, s.triangle_part, markers - 1), std::invalid_argument);
}

// A user's part indices with gaps (or a part outvoted on every triangle) are dropped and the
// others renumbered in order, rather than left as empty parts nothing downstream can fit.
TEST(PartSegmentation, UnusedPartIndicesAreDroppedAndTheRestRenumbered) {
  const int frames = 20;
  const ArticulatedLimb limb = make_articulated_limb(3, frames);
  std::vector<int> gaps = limb.segment;
  for (int& p : gaps) p = p == 0 ? 0 : (p == 1 ? 2 : 5);
  // One marker of segment 0 alone in part 7: outvoted on each of its triangles.
  gaps[limb.marker(1, 3)] = 7;
  const PartSegmentation s = segmentation_from_assignment(limb.reference, limb.triangles, limb.positions, frames, gaps,
                                                          AssignmentKind::PerMarker);
  EXPECT_EQ(s.part_count, 3);
  EXPECT_EQ(s.unused_parts, (std::vector<int>{1, 3, 4, 6, 7}));
  const PartSegmentation plain = segmentation_from_assignment(limb.reference, limb.triangles, limb.positions, frames,
                                                              limb.segment, AssignmentKind::PerMarker);
  EXPECT_EQ(s.triangle_part, plain.triangle_part);
  EXPECT_TRUE(plain.unused_parts.empty());
  // An index no smaller than the triangle count is refused, not turned into a list of empties.
  std::vector<int> typo = limb.segment;
  typo[0] = static_cast<int>(limb.triangles.size());
  EXPECT_THROW(segmentation_from_assignment(limb.reference, limb.triangles, limb.positions, frames, typo,
                                            AssignmentKind::PerMarker),
               std::invalid_argument);
}

}  // namespace
}  // namespace skinstream
