#include "core/gap_filler.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "support/allocation_counter.h"
#include "core/offline/subject_builder.h"
#include "support/synthetic_arm.h"
#include "support/synthetic_limb.h"

namespace skinstream {
namespace {

struct Fixture {
  explicit Fixture(test::LimbOptions o = {}) : options(o), truth(test::make_limb_capture(o)), model(build_subject(truth, {})) {}
  test::LimbOptions options;
  Capture truth;
  SubjectModel model;
};

struct Frame {
  explicit Frame(int n) : labelled(n), positions(n), status(n) {}
  std::vector<Vec3> labelled, unlabelled;
  std::vector<int> ids;
  std::vector<Vec3> positions;
  std::vector<MarkerStatus> status;
  FillStats run(GapFiller& filler) { return filler.run({labelled, unlabelled, ids}, {positions, status}); }
};

void load(const Capture& c, int f, Frame& frame) {
  for (int p = 0; p < c.point_count(); ++p) frame.labelled[p] = c.at(f, p);
  frame.unlabelled.clear();
  frame.ids.clear();
}

// A marker in the middle of the limb and the opposite one.
constexpr int kMiddle = 3 * 8 + 2;
constexpr int kOther = 3 * 8 + 6;

TEST(GapFiller, RejectsInputOfTheWrongSize) {
  Fixture fx;
  GapFiller filler(fx.model);
  Frame frame(fx.model.marker_count() - 1);
  std::vector<Vec3> positions(fx.model.marker_count());
  std::vector<MarkerStatus> status(fx.model.marker_count());
  EXPECT_FALSE(filler.run({frame.labelled, {}, {}}, {positions, status}).ok);
}

TEST(GapFiller, RejectsIdsThatDoNotMatchThePoints) {
  Fixture fx;
  GapFiller filler(fx.model);
  Frame frame(fx.model.marker_count());
  load(fx.truth, 0, frame);
  frame.unlabelled = {Vec3(1, 2, 3)};
  frame.ids = {1, 2};
  EXPECT_FALSE(frame.run(filler).ok);
}

TEST(GapFiller, FillsARigidNeighbourhoodExactly) {
  test::LimbOptions o;
  o.bulge = o.twist = 0.0;
  Fixture fx(o);
  GapFiller filler(fx.model);
  Frame frame(fx.model.marker_count());
  for (int f = 0; f < 200; ++f) {
    load(fx.truth, f, frame);
    if (f >= 50) frame.labelled[kMiddle] = frame.labelled[kOther] = missing_point();
    ASSERT_TRUE(frame.run(filler).ok);
    if (f >= 50) {
      EXPECT_EQ(frame.status[kMiddle], MarkerStatus::FilledPca);
      EXPECT_LT((frame.positions[kMiddle] - fx.truth.at(f, kMiddle)).norm(), 1e-6) << "frame " << f;
      EXPECT_LT((frame.positions[kOther] - fx.truth.at(f, kOther)).norm(), 1e-6);
    }
  }
}

double mean_fill_error(const Fixture& fx, const GapFillerOptions& options, int hide_ring_members) {
  GapFiller filler(fx.model, options);
  Frame frame(fx.model.marker_count());
  double sum = 0;
  int count = 0;
  const int ring_first = fx.model.ring_offsets[kMiddle];
  for (int f = 0; f < fx.truth.frame_count; ++f) {
    load(fx.truth, f, frame);
    if (f >= 100) {
      frame.labelled[kMiddle] = missing_point();
      for (int k = 0; k < hide_ring_members; ++k) frame.labelled[fx.model.ring[ring_first + k]] = missing_point();
    }
    frame.run(filler);
    if (f >= 100) {
      sum += (frame.positions[kMiddle] - fx.truth.at(f, kMiddle)).norm();
      ++count;
    }
  }
  return sum / count;
}

TEST(GapFiller, PcaBeatsTheRigidEstimateOnADeformingLimb) {
  Fixture fx;
  GapFillerOptions rigid;
  rigid.use_pca = false;
  GapFillerOptions pca;
  pca.continuity_seconds = rigid.continuity_seconds = 0.0;  // compare the estimators alone
  pca.carry_from_gap_start = rigid.carry_from_gap_start = false;
  const double rigid_error = mean_fill_error(fx, rigid, 0);
  const double pca_error = mean_fill_error(fx, pca, 0);
  const double spacing = fx.model.neighbour_distance(kMiddle);
  EXPECT_LT(pca_error, 0.5 * rigid_error);
  EXPECT_LT(pca_error / spacing, 0.02);  // the paper reports about 0.02 on real data
}

// A carry from the gap's start weighs less as the gap ages, by the gap's own age: once the
// gap-start continuity has faded, the fill is the same with it or without it. (The age was once
// counted by the continuity code alone: without it a carry kept its first frame's weight for the
// whole gap, and a second gap started at the first one's age.)
TEST(GapFiller, ACarryAgesWithItsGapWhetherContinuityIsOnOrOff) {
  test::LimbOptions o;
  o.frames = 1800;
  Fixture fx(o);
  GapFillerOptions with_continuity, without;
  without.continuity_seconds = 0.0;
  GapFiller a(fx.model, with_continuity), b(fx.model, without);
  Frame fa(fx.model.marker_count()), fb(fx.model.marker_count());
  const int faded = static_cast<int>(5 * with_continuity.continuity_seconds * with_continuity.rate_hz);
  double largest = 0.0, spread = 0.0;  // the fills' largest difference; the fill's largest error
  for (int f = 0; f < fx.truth.frame_count; ++f) {
    load(fx.truth, f, fa);
    load(fx.truth, f, fb);
    const bool first_gap = f >= 300 && f < 400, second_gap = f >= 520;
    if (first_gap || second_gap) {  // the marker and all but three of its ring: the carry weighs in
      fa.labelled[kMiddle] = fb.labelled[kMiddle] = missing_point();
      for (int k = fx.model.ring_offsets[kMiddle]; k < fx.model.ring_offsets[kMiddle + 1] - 3; ++k)
        fa.labelled[fx.model.ring[k]] = fb.labelled[fx.model.ring[k]] = missing_point();
    }
    fa.run(a);
    fb.run(b);
    if (second_gap && f >= 520 + faded) {
      largest = std::max(largest, (fa.positions[kMiddle] - fb.positions[kMiddle]).norm());
      spread = std::max(spread, (fa.positions[kMiddle] - fx.truth.at(f, kMiddle)).norm());
    }
  }
  // What is left is the faded offset (e^-5 of it): well under the fill's own error. (With the age
  // counted by the continuity code, the two fills differed by more than that error.)
  EXPECT_LT(largest, 0.01 * spread);
}

// A gap whose first frame has no neighbourhood rotation to keep an offset in (the whole limb
// hidden then) starts with no continuity offset, not with what was left of the marker's last one.
TEST(GapFiller, AGapStartsWithNoOffsetLeftFromTheMarkersLastGap) {
  Fixture fx;
  GapFillerOptions options;  // nothing else kept from frame to frame that the first gap would change
  options.carry_from_gap_start = options.use_regions = options.calibrate_rings = false;
  GapFillerOptions no_continuity = options;
  no_continuity.continuity_seconds = 0.0;
  GapFiller a(fx.model, options), b(fx.model, options), plain(fx.model, no_continuity);
  const int n = fx.model.marker_count();
  Frame fa(n), fb(n), fp(n);
  double first_offset = 0.0, left = 0.0;
  for (int f = 0; f < 240; ++f) {
    for (Frame* frame : {&fa, &fb, &fp}) {
      load(fx.truth, f, *frame);
      if (f == 200)
        for (Vec3& p : frame->labelled) p = missing_point();
      if (f >= 200 && f < 230) frame->labelled[kMiddle] = missing_point();
    }
    if (f >= 100 && f < 105) {  // a's first gap: the marker and all but three of its ring, a poorer estimate
      fa.labelled[kMiddle] = fp.labelled[kMiddle] = missing_point();
      for (int k = fx.model.ring_offsets[kMiddle]; k < fx.model.ring_offsets[kMiddle + 1] - 3; ++k)
        fa.labelled[fx.model.ring[k]] = fp.labelled[fx.model.ring[k]] = missing_point();
    }
    fa.run(a);
    fb.run(b);
    fp.run(plain);
    if (f == 100) first_offset = (fa.positions[kMiddle] - fp.positions[kMiddle]).norm();
    if (f > 200 && f < 230) left = std::max(left, (fa.positions[kMiddle] - fb.positions[kMiddle]).norm());
  }
  ASSERT_GT(first_offset, 1.0) << "the first gap starts with an offset";
  EXPECT_LT(left, 1e-9);
}

// A marker that slides on the skin after training (a loose one) makes every one-ring opinion that
// reads it a poor judge, and every opinion of where it is a poor one too. Checked while the ring
// is seen, each such opinion comes to claim less (its variance scaled up); the others do not.
TEST(GapFiller, AnOpinionThatLatelyMissedClaimsLess) {
  Fixture fx;
  const int loose = fx.model.ring[fx.model.ring_offsets[kMiddle]];
  Capture live = fx.truth;
  for (int f = 0; f < live.frame_count; ++f)  // 25 mm back and forth, at 0.9 Hz
    live.positions[f * live.point_count() + loose] += Vec3(0, 0, 25.0 * std::sin(2.0 * M_PI * 0.9 * f / fx.options.rate));
  auto calibrations = [&](const Capture& capture, bool calibrate) {
    GapFillerOptions options;
    options.calibrate_rings = calibrate;
    GapFiller filler(fx.model, options);
    Frame frame(fx.model.marker_count());
    for (int f = 0; f < capture.frame_count; ++f) {
      load(capture, f, frame);
      frame.run(filler);
    }
    double about_loose = 1e300, others = 0.0;  // least among the opinions of or by it, most among rings without it
    for (int j = 0; j < fx.model.marker_count(); ++j) {
      const int first = fx.model.ring_offsets[j], last = fx.model.ring_offsets[j + 1];
      const bool ring_has_loose = j == loose || std::count(fx.model.ring.begin() + first, fx.model.ring.begin() + last, loose) > 0;
      for (int k = first; k < last; ++k) {
        if (j == loose || fx.model.ring[k] == loose) about_loose = std::min(about_loose, filler.ring_calibration(k));
        else if (!ring_has_loose) others = std::max(others, filler.ring_calibration(k));
      }
    }
    return std::pair{about_loose, others};
  };
  const auto [loose_claims, other_claims] = calibrations(live, true);
  EXPECT_GT(loose_claims, 4.0);  // where it is, and what its own ring says, each at least 4x the variance
  EXPECT_LT(other_claims, 1.5);  // rings without it: as calibrated offline
  const auto [clean_claims, unused] = calibrations(fx.truth, true);
  EXPECT_LT(clean_claims, 1.5);  // the same opinions on the capture it was trained on
  EXPECT_EQ(calibrations(live, false).first, 1.0);  // off: the offline calibration alone
}

TEST(GapFiller, PcaFitsWithMissingEntriesInTheRing) {
  Fixture fx;
  GapFillerOptions o;
  o.continuity_seconds = 0.0;
  const double spacing = fx.model.neighbour_distance(kMiddle);
  // Hide the marker and two of its neighbours: the remaining ring members drive the fit.
  EXPECT_LT(mean_fill_error(fx, o, 2) / spacing, 0.05);
}

TEST(GapFiller, RelabelsAnUnlabelledPointNearTheEstimateAndIgnoresAFarOne) {
  Fixture fx;
  GapFiller filler(fx.model);
  Frame frame(fx.model.marker_count());
  const double eps1 = fx.model.parameters.alpha1 * fx.model.neighbour_distance(kMiddle);
  for (int f = 0; f < 20; ++f) {
    load(fx.truth, f, frame);
    frame.run(filler);
  }
  load(fx.truth, 20, frame);
  const Vec3 truth = frame.labelled[kMiddle];
  frame.labelled[kMiddle] = missing_point();
  frame.unlabelled = {truth + Vec3(0, 0, 3.0 * eps1), truth + Vec3(0.5, 0, 0)};  // a ghost, the marker
  frame.ids = {100, 101};
  const FillStats s = frame.run(filler);
  EXPECT_EQ(s.relabelled, 1);
  EXPECT_EQ(frame.status[kMiddle], MarkerStatus::Relabelled);
  EXPECT_LT((frame.positions[kMiddle] - (truth + Vec3(0.5, 0, 0))).norm(), 1e-12);

  // Only the ghost: nothing within eps1, so the marker is filled, not relabelled.
  load(fx.truth, 21, frame);
  const Vec3 truth21 = frame.labelled[kMiddle];
  frame.labelled[kMiddle] = missing_point();
  frame.unlabelled = {truth21 + Vec3(0, 0, 3.0 * eps1)};
  frame.ids = {100};
  frame.run(filler);
  EXPECT_EQ(frame.status[kMiddle], MarkerStatus::FilledPca);
}

TEST(GapFiller, KeepsAFragmentWhileWithinEps2AndDropsItBeyond) {
  Fixture fx;
  GapFiller filler(fx.model);
  Frame frame(fx.model.marker_count());
  const double spacing = fx.model.neighbour_distance(kMiddle);
  const double eps1 = fx.model.parameters.alpha1 * spacing, eps2 = fx.model.parameters.alpha2 * spacing;
  for (int f = 0; f < 60; ++f) {
    load(fx.truth, f, frame);
    const Vec3 truth = frame.labelled[kMiddle];
    if (f >= 10) {
      frame.labelled[kMiddle] = missing_point();
      // The broken trajectory comes back as fragment 7: first close, then drifting to between
      // eps1 and eps2 (kept), then beyond eps2 (dropped).
      const double drift = f < 30 ? 0.2 * eps1 : f < 45 ? 0.5 * (eps1 + eps2) : 1.5 * eps2;
      frame.unlabelled = {truth + Vec3(drift, 0, 0)};
      frame.ids = {7};
    }
    frame.run(filler);
    if (f >= 10 && f < 45) {
      EXPECT_EQ(frame.status[kMiddle], MarkerStatus::Relabelled) << "frame " << f;
    }
    if (f >= 45) {
      EXPECT_NE(frame.status[kMiddle], MarkerStatus::Relabelled) << "frame " << f;
    }
  }
}

TEST(GapFiller, RejoinsSwappedLabels) {
  Fixture fx;
  GapFiller filler(fx.model);
  Frame frame(fx.model.marker_count());
  const int a = kMiddle, b = fx.model.ring[fx.model.ring_offsets[kMiddle]];  // neighbours
  for (int f = 0; f < 40; ++f) {
    load(fx.truth, f, frame);
    if (f >= 20) std::swap(frame.labelled[a], frame.labelled[b]);  // the capture system swapped them
    const FillStats s = frame.run(filler);
    if (f >= 20) {
      EXPECT_EQ(s.rejected_labels, 2) << "frame " << f;
      EXPECT_EQ(frame.status[a], MarkerStatus::Relabelled);
      EXPECT_EQ(frame.status[b], MarkerStatus::Relabelled);
      EXPECT_LT((frame.positions[a] - fx.truth.at(f, a)).norm(), 1e-9);
      EXPECT_LT((frame.positions[b] - fx.truth.at(f, b)).norm(), 1e-9);
    }
  }
}

// The overruled wrist of a real capture: a marker comes back from a gap where its estimate went
// wrong (here it slid over the skin while hidden, which its ring cannot tell; there the hand
// moved, which a few forearm markers cannot tell), while four of its ring members are still
// missing. Its true measurement is then farther than eps2 from where the filler had it, and
// nothing else explains the point (it lies between the neighbours' places): the measurement
// stands, in every frame, untouched.
TEST(GapFiller, KeepsATrueMeasurementItsPoorEstimateDisagreesWith) {
  Fixture fx;
  GapFiller filler(fx.model);
  Frame frame(fx.model.marker_count());
  const double eps2 = fx.model.parameters.alpha2 * fx.model.neighbour_distance(kMiddle);
  // Between the next marker along the limb and the next one around it.
  const Vec3 diagonal = (fx.truth.at(0, kMiddle + 8) + fx.truth.at(0, kMiddle + 1) - 2.0 * fx.truth.at(0, kMiddle)).normalized();
  Vec3 before_return = Vec3::Zero();
  for (int f = 0; f < 300; ++f) {
    load(fx.truth, f, frame);
    frame.labelled[kMiddle] += 1.2 * eps2 * std::clamp((f - 100) / 100.0, 0.0, 1.0) * diagonal;
    if (f >= 100 && f < 200) frame.labelled[kMiddle] = missing_point();
    if (f >= 100 && f < 210)
      for (int k = 0; k < 4; ++k) frame.labelled[fx.model.ring[fx.model.ring_offsets[kMiddle] + k]] = missing_point();
    const FillStats s = frame.run(filler);
    if (f == 199) before_return = frame.positions[kMiddle];
    if (f < 200) continue;
    if (f == 200) {
      ASSERT_GT((frame.labelled[kMiddle] - before_return).norm(), eps2) << "the estimate must disagree for this test";
      for (int j = 0; j < fx.model.marker_count(); ++j)
        if (j != kMiddle) {
          ASSERT_GT((frame.labelled[kMiddle] - fx.truth.at(f, j)).norm(),
                    fx.model.parameters.alpha1 * fx.model.neighbour_distance(j))
              << "no other marker may be where the point is";
        }
    }
    EXPECT_EQ(frame.status[kMiddle], MarkerStatus::Measured) << "frame " << f;
    EXPECT_EQ(frame.positions[kMiddle], frame.labelled[kMiddle]) << "frame " << f;
    EXPECT_EQ(s.rejected_labels, 0) << "frame " << f;
    EXPECT_EQ(s.changed_measured, 0) << "frame " << f;
  }
}

// The overruled wrist of a tennis serve: WRB's one-ring is a finger, a forearm and an upper arm
// marker, nearly on one line with the elbow straight and across the elbow, so when the elbow
// bends far beyond what training saw (0.2 rad there, 1.5 here) WRB's rigid estimate (eq. 2) goes
// wrong, towards WRA. WRA, missing with it (and with F1 and F2), is estimated on
// WRB's estimate. WRA returns while WRB is still missing, its true point nearer WRB's wrong
// estimate than WRB is: the measurement stands, untouched, in every frame.
// Before the rigid estimate's variance saw its members' leverage and carried on the variance of a
// member the chain only estimated, WRA's fill leaned on that chain and ended the gap 64 mm off
// (beyond eps2, 51 mm; 40 mm now), and at its return the label check read WRB's estimate, 26 mm
// from the point, as a swap and gave the point to WRB (frame 200: 1 measured sample changed, WRA
// output 19 mm from its measurement). Now none of the 60 frames changes it.
TEST(GapFiller, KeepsATrueMeasurementNextToAChainEstimateOffAcrossABentElbow) {
  using namespace test;
  ArmOptions training;
  training.seed = 3;  // before: overruled with 8 of 10 training noise seeds (not 1, 7); now with none
  training.elbow = [](int f) { return 0.1 * (1.0 - std::cos(2.0 * M_PI * 0.3 * f / 120.0)); };
  const std::vector<std::array<int, 3>> triangles = arm_triangles();
  const SubjectModel model = build_subject(make_arm_capture(training), {}, &triangles);
  const Vec3 upa = model.reference_positions[kUPA], frm = model.reference_positions[kFRM], fin = model.reference_positions[kFIN];
  ASSERT_LT((upa - frm).normalized().dot((fin - frm).normalized()), -std::cos(10.0 * M_PI / 180.0))
      << "WRB's ring must be nearly collinear in the reference pose (within 10 degrees of straight at FRM) for this test";

  ArmOptions live;
  live.frames = 260;
  live.seed = 2;
  live.elbow = [](int f) { return 1.5 * std::clamp((f - 100) / 80.0, 0.0, 1.0); };
  const Capture truth = make_arm_capture(live);
  GapFiller filler(model);
  Frame frame(model.marker_count());
  for (int f = 0; f < live.frames; ++f) {
    load(truth, f, frame);
    if (f >= 100) frame.labelled[kWRB] = frame.labelled[kF1] = frame.labelled[kF2] = missing_point();
    if (f >= 100 && f < 200) frame.labelled[kWRA] = missing_point();
    const FillStats s = frame.run(filler);
    if (f == 199) {
      const double off = (frame.positions[kWRB] - truth.at(f, kWRB)).norm();
      ASSERT_GT(off, 20.0) << "WRB's estimate must be more than 20 mm off for this test";
      ASSERT_LT((frame.positions[kWRB] - truth.at(f, kWRA)).norm(), off) << "and nearer WRA than WRB";
    }
    if (f < 200) continue;
    EXPECT_EQ(frame.status[kWRA], MarkerStatus::Measured) << "frame " << f << ": " << to_string(frame.status[kWRA]);
    EXPECT_EQ(frame.positions[kWRA], frame.labelled[kWRA])
        << "frame " << f << ": output " << (frame.positions[kWRA] - frame.labelled[kWRA]).norm() << " mm from the measurement";
    EXPECT_EQ(s.rejected_labels, 0) << "frame " << f;
    EXPECT_EQ(s.changed_measured, 0) << "frame " << f;
  }
}

// From frame 20 on, kMiddle's labelled point speeds away from kOther, by 0.3 eps2 a frame more
// each frame up to 1.5 eps2 a frame (with every other marker hidden when `alone`); every one of
// those frames, the measurement must stand. Returns how far it went, in eps2, and in how many
// frames it moved more than eps2.
struct SpeedingMarker {
  double travelled_eps2 = 0.0;
  int fast_frames = 0;
};

SpeedingMarker expect_a_speeding_marker_stands(bool alone, int frames) {
  Fixture fx;
  GapFiller filler(fx.model);
  Frame frame(fx.model.marker_count());
  const double eps2 = fx.model.parameters.alpha2 * fx.model.neighbour_distance(kMiddle);
  const Vec3 out = (fx.truth.at(0, kMiddle) - fx.truth.at(0, kOther)).normalized();
  SpeedingMarker run;
  for (int f = 0; f < frames; ++f) {
    load(fx.truth, f, frame);
    if (f >= 20) {
      if (alone)
        for (int j = 0; j < fx.model.marker_count(); ++j)
          if (j != kMiddle) frame.labelled[j] = missing_point();
      const double speed = std::min(f - 19, 5) * 0.3;
      run.travelled_eps2 += speed;
      run.fast_frames += speed > 1.0;
      frame.labelled[kMiddle] += run.travelled_eps2 * eps2 * out;
    }
    const FillStats s = frame.run(filler);
    if (f < 20) continue;
    EXPECT_EQ(frame.status[kMiddle], MarkerStatus::Measured) << "frame " << f;
    EXPECT_EQ(frame.positions[kMiddle], frame.labelled[kMiddle]) << "frame " << f;
    EXPECT_EQ(s.changed_measured, 0) << "frame " << f;
  }
  return run;
}

// A marker that nothing else can estimate (its whole neighbourhood hidden, as the serving hand of
// a 50 Hz tennis serve when its four markers all jumped more than eps2 at once) and that speeds up
// to more than eps2 a frame is suspect, but nothing speaks against it: no estimate of its own
// disagrees, no other marker reaches the point, and it keeps to its own track. Once, "explained by
// another" compared no marker's distance (infinity) with no estimate's (infinity) and rejected it.
TEST(GapFiller, KeepsAFastMarkerNothingElseCanEstimate) {
  EXPECT_GE(expect_a_speeding_marker_stands(true, 40).fast_frames, 15)
      << "the marker must move more than eps2 a frame for this test";
}

// A tracked marker that speeds away from its ring (a hand at a low frame rate moves more between
// frames than its neighbourhood model allows) is suspect, and its own estimate, from a ring seen
// whole, disagrees confidently. But it keeps to its own track, so nothing says it is another
// marker: the measurement stands. Once, a tracked point was rejected on its estimate alone.
TEST(GapFiller, KeepsATrackedMarkerOnItsOwnTrackItsEstimateDisagreesWith) {
  EXPECT_GT(expect_a_speeding_marker_stands(false, 30).travelled_eps2, 3.0)
      << "its estimate must disagree by more than eps2 for this test";
}

// Two neighbours return from a gap with their labels swapped, at a frame where the rest of the limb
// is hidden: neither has an estimate, so only their tracks speak. Each point is next to where
// the other marker was last estimated and a marker spacing from its own: both are rejected.
// Once, a point with no estimate of its own stood unless another marker's estimate reached it.
TEST(GapFiller, RejectsTwoLabelsSwappedWhereNeitherHasAnEstimate) {
  Fixture fx;
  GapFiller filler(fx.model);
  Frame frame(fx.model.marker_count());
  const int neighbour = fx.model.ring[fx.model.ring_offsets[kMiddle]];
  const double eps2 = fx.model.parameters.alpha2 * std::max(fx.model.neighbour_distance(kMiddle), fx.model.neighbour_distance(neighbour));
  for (int f = 0; f <= 30; ++f) {
    load(fx.truth, f, frame);
    if (f >= 20) frame.labelled[kMiddle] = frame.labelled[neighbour] = missing_point();
    if (f == 30) {
      for (int j = 0; j < fx.model.marker_count(); ++j) frame.labelled[j] = missing_point();
      frame.labelled[kMiddle] = fx.truth.at(f, neighbour);
      frame.labelled[neighbour] = fx.truth.at(f, kMiddle);
      ASSERT_GT((fx.truth.at(f, kMiddle) - fx.truth.at(f, neighbour)).norm(), eps2) << "the swapped labels must be suspect";
    }
    const FillStats s = frame.run(filler);
    if (f == 29) {
      ASSERT_NE(frame.status[kMiddle], MarkerStatus::Held) << "estimated during the gap";
      ASSERT_NE(frame.status[neighbour], MarkerStatus::Held);
    }
    if (f < 30) continue;
    EXPECT_EQ(s.rejected_labels, 2);
    EXPECT_NE(frame.positions[kMiddle], frame.labelled[kMiddle]);
    EXPECT_NE(frame.positions[neighbour], frame.labelled[neighbour]);
  }
}

// A marker comes back from a gap under the label of a neighbour that was itself missing: the
// point is far from the neighbour's estimate and next to the estimate of the marker it really
// is, which is missing. That explains it: it goes to that marker, and the neighbour is filled.
TEST(GapFiller, GivesAReturningPointToTheMissingMarkerItIs) {
  Fixture fx;
  GapFiller filler(fx.model);
  Frame frame(fx.model.marker_count());
  const int a = kMiddle, b = fx.model.ring[fx.model.ring_offsets[kMiddle]];
  for (int f = 0; f < 220; ++f) {
    load(fx.truth, f, frame);
    if (f >= 100 && f < 200) frame.labelled[a] = missing_point();
    if (f >= 140 && f < 150) frame.labelled[b] = missing_point();
    if (f >= 150 && f < 200) frame.labelled[b] = fx.truth.at(f, a);
    const FillStats s = frame.run(filler);
    if (f < 150 || f >= 200) continue;
    EXPECT_EQ(s.rejected_labels, 1) << "frame " << f;
    EXPECT_EQ(s.changed_measured, 1) << "frame " << f;
    EXPECT_EQ(frame.status[a], MarkerStatus::Relabelled) << "frame " << f;
    EXPECT_EQ(frame.positions[a], fx.truth.at(f, a)) << "frame " << f;
    EXPECT_EQ(frame.status[b], MarkerStatus::FilledPca) << "frame " << f;
  }
}

TEST(GapFiller, NeverOutputsNaN) {
  Fixture fx;
  GapFiller filler(fx.model);
  Frame frame(fx.model.marker_count());
  for (int f = 0; f < 30; ++f) {
    load(fx.truth, f, frame);
    if (f < 3 || f > 20)  // nothing at all, at the start and after some frames
      for (Vec3& p : frame.labelled) p = missing_point();
    if (f == 10) frame.labelled[0] = Vec3(std::nan(""), 1, 2);  // partly NaN
    frame.run(filler);
    for (const Vec3& p : frame.positions) ASSERT_TRUE(p.allFinite()) << "frame " << f;
  }
}

// reset() forgets the take: the next one is filled as a new filler fills it, bit for bit. The
// second take starts where the first one's markers are not: the limb moved so that the point
// standing for the middle marker lies where the opposite marker was last in the first take, and
// every marker but the middle one's ring is hidden. A filler that kept the first take's statuses
// (and so its tracks) filled this take's first frame otherwise.
TEST(GapFiller, AfterResetATakeIsFilledAsByANewFiller) {
  Fixture fx;
  const int n = fx.model.marker_count();
  GapFiller used(fx.model), fresh(fx.model);
  Frame frame(n), again(n);
  for (int f = 0; f < 40; ++f) {
    load(fx.truth, f, frame);
    frame.run(used);
  }
  const Vec3 opposite_last = fx.truth.at(39, kOther);
  used.reset();

  const Vec3 shift = opposite_last - fx.truth.at(100, kMiddle);
  std::vector<char> ring(n, 0);
  for (int k = fx.model.ring_offsets[kMiddle]; k < fx.model.ring_offsets[kMiddle + 1]; ++k)
    ring[fx.model.ring[k]] = 1;
  for (int f = 100; f < 130; ++f) {
    load(fx.truth, f, frame);
    for (Vec3& p : frame.labelled) p += shift;
    if (f == 100) {
      for (int i = 0; i < n; ++i)
        if (!ring[i]) frame.labelled[i] = missing_point();
      frame.unlabelled = {fx.truth.at(f, kMiddle) + shift};
      frame.ids = {7};
    }
    again.labelled = frame.labelled;
    again.unlabelled = frame.unlabelled;
    again.ids = frame.ids;
    frame.run(used);
    again.run(fresh);
    if (f == 100) {
      EXPECT_EQ(again.status[kMiddle], MarkerStatus::Relabelled);
    }
    for (int i = 0; i < n; ++i) {
      ASSERT_EQ(frame.status[i], again.status[i]) << "frame " << f << ", marker " << i;
      ASSERT_EQ(frame.positions[i], again.positions[i]) << "frame " << f << ", marker " << i;
    }
  }
}

// Also with new relabels on probation (confirm_frames 6) and the fragments and revocations asked for.
TEST(GapFiller, AllocatesNothingPerFrame) {
  Fixture fx;
  GapFillerOptions options;
  options.confirm_frames = 6;
  GapFiller filler(fx.model, options);
  Frame frame(fx.model.marker_count());
  std::vector<int> fragments(fx.model.marker_count()), revoked(fx.model.marker_count());
  auto run = [&] { filler.run({frame.labelled, frame.unlabelled, frame.ids}, {frame.positions, frame.status, fragments, revoked}); };
  frame.unlabelled.reserve(8);
  frame.ids.reserve(8);
  const int b = fx.model.ring[fx.model.ring_offsets[kOther]];
  auto make = [&](int f) {
    load(fx.truth, f, frame);
    const Vec3 truth = frame.labelled[kMiddle];
    frame.labelled[kMiddle] = missing_point();
    if (f % 3 == 0) frame.labelled[kOther] = missing_point();
    if (f % 5 == 0) std::swap(frame.labelled[kOther], frame.labelled[b]);  // labels to judge
    if (f % 7 < 3) frame.labelled[fx.model.ring[fx.model.ring_offsets[kMiddle]]] = missing_point();  // two of a ring
    if (f % 2 == 0) {
      frame.unlabelled.push_back(truth);
      frame.ids.push_back(f % 4);
    }
  };
  for (int f = 0; f < 10; ++f) {
    make(f);
    run();
  }
  test::CountAllocations counter;
  for (int f = 10; f < 200; ++f) {
    make(f);
    run();
  }
  EXPECT_EQ(counter.count(), 0u);
}

}  // namespace
}  // namespace skinstream
