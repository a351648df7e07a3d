#include "core/gap_start_carry.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <vector>

#include "core/offline/subject_builder.h"
#include "support/allocation_counter.h"
#include "support/synthetic_limb.h"

namespace skinstream {
namespace {

constexpr int kCarriedMarker = 3 * 8 + 2;  // a marker in the middle of the limb
constexpr double kCarryRateHz = 120.0;

struct CarryLimb {
  CarryLimb() : truth(test::make_limb_capture()), model(build_subject(truth, {})) {}
  Capture truth;
  SubjectModel model;

  // The reference pose turned and moved as one rigid body.
  std::vector<Vec3> rigid_frame(int f) const {
    const double t = f / kCarryRateHz;
    const Eigen::Matrix3d r = (Eigen::AngleAxisd(0.9 * std::sin(1.3 * t), Vec3::UnitZ()) *
                               Eigen::AngleAxisd(0.4 * std::sin(0.7 * t), Vec3::UnitX()))
                                  .toRotationMatrix();
    const Vec3 shift(300.0 * std::sin(0.9 * t), 150.0 * t, 20.0 * std::cos(2.0 * t));
    std::vector<Vec3> positions;
    for (const Vec3& p : model.reference_positions) positions.push_back(r * p + shift);
    return positions;
  }
  std::vector<Vec3> truth_frame(int f) const {
    std::vector<Vec3> positions(truth.point_count());
    for (int p = 0; p < truth.point_count(); ++p) positions[p] = truth.at(f, p);
    return positions;
  }
};

// Runs `carry` over frames [0, end) of `frame_at`, everything observed, as the filler does after
// each frame; the gap of `marker` starts at `gap_start` (its last seen frame the one before).
template <class FrameAt>
void run_with_gap(GapStartCarry& carry, const FrameAt& frame_at, int markers, int end, int marker = -1,
                  int gap_start = -1) {
  std::vector<char> observed(markers, 1);
  const std::vector<MarkerStatus> measured(markers, MarkerStatus::Measured);
  for (int f = 0; f < end; ++f) {
    if (marker >= 0) observed[marker] = f < gap_start;
    if (f == gap_start) carry.remember_gap_start(marker, f, frame_at(f - 1), measured);
    carry.check(f, frame_at(f), observed);
  }
}

// On a rigid body the carry from the gap start is exact however long the gap, and claims the
// least it may: the model's residual.
TEST(GapStartCarry, FollowsARigidMotionOfItsAnchors) {
  CarryLimb fx;
  const int n = fx.model.marker_count();
  GapStartCarry carry(fx.model, kCarryRateHz);
  auto frame_at = [&](int f) { return fx.rigid_frame(f); };
  run_with_gap(carry, frame_at, n, 700, kCarriedMarker, 400);
  std::vector<char> observed(n, 1);
  observed[kCarriedMarker] = 0;
  Vec3 carried;
  double variance = 0.0;
  ASSERT_TRUE(carry.carried(kCarriedMarker, 699, fx.rigid_frame(699), observed, carried, variance));
  EXPECT_LT((carried - fx.rigid_frame(699)[kCarriedMarker]).norm(), 1e-6);
  EXPECT_GT((fx.rigid_frame(699)[kCarriedMarker] - fx.rigid_frame(399)[kCarriedMarker]).norm(),
            100.0);  // it did move
  EXPECT_LT(carry.drift(kCarriedMarker), 1e-12);
  EXPECT_EQ(variance, fx.model.pca[kCarriedMarker].residual_variance);
  EXPECT_EQ(carry.gap_start_frame(kCarriedMarker), 400);
}

// Every half second while a marker is seen its carry is checked; no opinion before four checks.
TEST(GapStartCarry, GivesNoOpinionBeforeItsDriftIsKnown) {
  CarryLimb fx;
  const int n = fx.model.marker_count();
  auto frame_at = [&](int f) { return fx.rigid_frame(f); };
  std::vector<char> observed(n, 1);
  observed[kCarriedMarker] = 0;
  Vec3 carried;
  double variance = 0.0;
  GapStartCarry early(fx.model, kCarryRateHz);  // snapshots at 0, 60, 120, 180: three checks
  run_with_gap(early, frame_at, n, 200, kCarriedMarker, 190);
  EXPECT_EQ(early.checks(kCarriedMarker), 3);
  EXPECT_FALSE(early.carried(kCarriedMarker, 199, fx.rigid_frame(199), observed, carried, variance));
  GapStartCarry later(fx.model, kCarryRateHz);
  run_with_gap(later, frame_at, n, 260, kCarriedMarker, 250);
  EXPECT_EQ(later.checks(kCarriedMarker), 4);
  EXPECT_TRUE(later.carried(kCarriedMarker, 259, fx.rigid_frame(259), observed, carried, variance));
}

// Where the anchors do not move rigidly with the marker (the limb bulges and twists), the carry
// drifts, and its variance grows with the gap's age.
TEST(GapStartCarry, ClaimsLessAsItsGapAges) {
  CarryLimb fx;
  const int n = fx.model.marker_count();
  GapStartCarry carry(fx.model, kCarryRateHz);
  auto frame_at = [&](int f) { return fx.truth_frame(f); };
  run_with_gap(carry, frame_at, n, 301, kCarriedMarker, 300);
  ASSERT_GT(carry.drift(kCarriedMarker), 0.0);
  std::vector<char> observed(n, 1);
  observed[kCarriedMarker] = 0;
  Vec3 soon, late;
  double soon_variance = 0.0, late_variance = 0.0;
  ASSERT_TRUE(carry.carried(kCarriedMarker, 305, fx.truth_frame(305), observed, soon, soon_variance));
  ASSERT_TRUE(carry.carried(kCarriedMarker, 500, fx.truth_frame(500), observed, late, late_variance));
  EXPECT_GT(late_variance, 10.0 * soon_variance);
}

// With fewer than three anchors seen both at the gap start and now, no carry.
TEST(GapStartCarry, NeedsThreeAnchorsSeenThenAndNow) {
  CarryLimb fx;
  const int n = fx.model.marker_count();
  GapStartCarry carry(fx.model, kCarryRateHz);
  auto frame_at = [&](int f) { return fx.rigid_frame(f); };
  run_with_gap(carry, frame_at, n, 400, kCarriedMarker, 350);
  std::vector<char> observed(n, 1);
  observed[kCarriedMarker] = 0;
  const int first = fx.model.anchor_offsets[kCarriedMarker],
            last = fx.model.anchor_offsets[kCarriedMarker + 1];
  ASSERT_GE(last - first, 3);
  for (int k = first; k < last - 2; ++k) observed[fx.model.anchors[k]] = 0;  // two left
  Vec3 carried;
  double variance = 0.0;
  EXPECT_FALSE(carry.carried(kCarriedMarker, 399, fx.rigid_frame(399), observed, carried, variance));
  observed[fx.model.anchors[first]] = 1;  // three again
  EXPECT_TRUE(carry.carried(kCarriedMarker, 399, fx.rigid_frame(399), observed, carried, variance));
}

TEST(GapStartCarry, ResetForgetsGapsAndDrift) {
  CarryLimb fx;
  const int n = fx.model.marker_count();
  GapStartCarry carry(fx.model, kCarryRateHz);
  auto frame_at = [&](int f) { return fx.truth_frame(f); };
  run_with_gap(carry, frame_at, n, 400, kCarriedMarker, 350);
  ASSERT_GE(carry.checks(kCarriedMarker), 4);
  carry.reset();
  EXPECT_EQ(carry.checks(kCarriedMarker), 0);
  EXPECT_EQ(carry.drift(kCarriedMarker), 0.0);
  std::vector<char> observed(n, 1);
  observed[kCarriedMarker] = 0;
  Vec3 carried;
  double variance = 0.0;
  EXPECT_FALSE(carry.carried(kCarriedMarker, 399, fx.truth_frame(399), observed, carried, variance));
}

TEST(GapStartCarry, AllocatesNothingPerFrame) {
  CarryLimb fx;
  const int n = fx.model.marker_count();
  GapStartCarry carry(fx.model, kCarryRateHz);
  std::vector<std::vector<Vec3>> frames;
  for (int f = 0; f < 400; ++f) frames.push_back(fx.truth_frame(f));
  std::vector<char> observed(n, 1);
  const std::vector<MarkerStatus> measured(n, MarkerStatus::Measured);
  Vec3 carried;
  double variance = 0.0;
  test::CountAllocations counter;
  for (int f = 1; f < 400; ++f) {
    observed[kCarriedMarker] = f < 300;
    if (f == 300) carry.remember_gap_start(kCarriedMarker, f, frames[f - 1], measured);
    if (f >= 300) carry.carried(kCarriedMarker, f, frames[f], observed, carried, variance);
    carry.check(f, frames[f], observed);
  }
  EXPECT_EQ(counter.count(), 0u);
}

}  // namespace
}  // namespace skinstream
