#include "core/label_check.h"

#include <gtest/gtest.h>

#include <limits>
#include <optional>
#include <vector>

#include "support/allocation_counter.h"

namespace skinstream {
namespace {

using S = MarkerStatus;

// Four markers 100 mm apart on a line, each with the others as its one-ring; eps2 of 20 mm and
// eps1 of 50 mm for every marker.
SubjectModel line_of_four() {
  SubjectModel model;
  model.marker_names = {"a", "b", "c", "d"};
  model.ring_offsets = {0};
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j)
      if (j != i) model.ring.push_back(j);
    model.ring_offsets.push_back(static_cast<int>(model.ring.size()));
  }
  return model;
}

std::vector<Vec3> line_at(double x) {
  return {Vec3(x, 0, 0), Vec3(x + 100, 0, 0), Vec3(x + 200, 0, 0), Vec3(x + 300, 0, 0)};
}

// The filler's expectations from a table: a position per marker (or none) and its variance.
struct TableExpectation final : MarkerExpectation {
  std::vector<std::optional<Vec3>> position = std::vector<std::optional<Vec3>>(4);
  std::vector<double> variance = std::vector<double>(4, 1.0);
  bool expected(int marker, Vec3& out, double* out_variance) override {
    if (!position[marker]) return false;
    out = *position[marker];
    if (out_variance) *out_variance = variance[marker];
    return true;
  }
};

struct LabelFixture {
  SubjectModel model = line_of_four();
  LabelCheck check{model};
  MarkerTracks tracks{4};
  std::vector<double> eps1 = std::vector<double>(4, 50.0);
  std::vector<double> eps2 = std::vector<double>(4, 20.0);
  std::vector<Vec3> points;
  std::vector<char> observed = std::vector<char>(4, 1);
  std::vector<int> missing;
  std::vector<char> estimated = std::vector<char>(4, 0);
  std::vector<Vec3> estimate = std::vector<Vec3>(4, Vec3::Zero());
  TableExpectation expectation;

  // The line measured at x = 0 and then at x = 10 (10 mm a frame along x), then this frame's points.
  explicit LabelFixture(std::vector<Vec3> now) : points(std::move(now)) {
    const std::vector<S> measured(4, S::Measured);
    tracks.advance(line_at(0), measured);
    tracks.advance(line_at(10), measured);
  }
  FrameEstimates frame() const { return {points, observed, missing, estimated, estimate, eps1, tracks}; }
  bool rejects(int i) { return check.rejects(i, frame(), eps2, expectation); }
  // Marker j missing this frame, its eq. 2 estimate and its expected position at `at`.
  void missing_expected_at(int j, const Vec3& at) {
    missing = {j};
    observed[j] = 0;
    estimated[j] = 1;
    estimate[j] = at;
    expectation.position[j] = at;
  }
};

TEST(LabelCheck, PointsThatMoveWithTheirRingAreNotSuspect) {
  // The whole line moved 35 mm in one frame, beyond eps2 from each one's last position: moving
  // with its neighbours, no label is doubted.
  LabelFixture fx(line_at(45));
  fx.check.find_suspects(fx.points, fx.observed, fx.eps2, fx.tracks);
  EXPECT_TRUE(fx.check.suspects().empty());
  EXPECT_EQ(fx.observed, std::vector<char>(4, 1));
}

TEST(LabelCheck, APointThatLeftItsRingIsHeldBack) {
  std::vector<Vec3> now = line_at(20);
  // b 25 mm off where the rest carried it (c's move takes it 5 mm along); c 15 mm off where
  // its ring carried it, and b's move takes that to 17 mm: within eps2.
  now[1] += Vec3(0, 25, 0);
  now[2] += Vec3(0, 0, 15);
  LabelFixture fx(now);
  fx.check.find_suspects(fx.points, fx.observed, fx.eps2, fx.tracks);
  ASSERT_EQ(fx.check.suspects().size(), 1u);
  EXPECT_EQ(fx.check.suspects()[0], 1);
  EXPECT_EQ(fx.observed, (std::vector<char>{1, 0, 1, 1}));
}

TEST(LabelCheck, WithFewerThanTwoOfItsRingSeenAPointIsJudgedByItsLastPosition) {
  // b's ring has only a seen: the whole line jumped 35 mm, and b with it, but nothing carries it.
  LabelFixture fx(line_at(45));
  fx.observed = {1, 1, 0, 0};
  fx.check.find_suspects(fx.points, fx.observed, fx.eps2, fx.tracks);
  // a's ring has only b seen too: both are off their last positions by 35 mm.
  EXPECT_EQ(std::vector<int>(fx.check.suspects().begin(), fx.check.suspects().end()),
            (std::vector<int>{0, 1}));
}

TEST(LabelCheck, AMarkerHeldLastFrameIsNeverSuspect) {
  // d is 30 mm from its held position: beyond eps2 were it judged (it drags the others' carried
  // positions by 10 mm, within theirs).
  LabelFixture fx(line_at(20));
  fx.points[3] += Vec3(0, 30, 0);
  std::vector<S> statuses(4, S::Measured);
  statuses[3] = S::Held;
  fx.tracks.advance(line_at(20), statuses);
  fx.check.find_suspects(fx.points, fx.observed, fx.eps2, fx.tracks);
  EXPECT_TRUE(fx.check.suspects().empty());
}

TEST(LabelCheck, ASuspectItsOwnEstimateAgreesWithStands) {
  LabelFixture fx(line_at(20));
  fx.expectation.position[1] = fx.points[1] + Vec3(0, 5, 0);
  fx.expectation.variance[1] = 4.0;  // 5 mm is 2.5 standard deviations: not a confident miss
  EXPECT_FALSE(fx.rejects(1));
}

TEST(LabelCheck, ASwapIsRejectedWhenAnotherMarkerExplainsThePointClearlyBetter) {
  // b's point is 40 mm from b's estimate and 10 mm from missing marker c's.
  LabelFixture fx(line_at(20));
  fx.expectation.position[1] = fx.points[1] + Vec3(0, 40, 0);
  fx.missing_expected_at(2, fx.points[1] + Vec3(0, 10, 0));
  EXPECT_TRUE(fx.rejects(1));
  // c farther than half of b's own miss (25 of 40 mm): not clearly better, and b kept to its
  // own track (10 mm a frame along x): it stands.
  fx.expectation.position[2] = fx.points[1] + Vec3(0, 25, 0);
  EXPECT_FALSE(fx.rejects(1));
  // A marker that is measured this frame explains nothing.
  fx.expectation.position[2] = fx.estimate[2];
  fx.observed[2] = 1;
  EXPECT_FALSE(fx.rejects(1));
}

TEST(LabelCheck, APointItsEstimateDisagreesWithStandsOnItsOwnTrackAndNotOffIt) {
  std::vector<Vec3> now = line_at(20);
  LabelFixture on_track(now);
  on_track.expectation.position[1] = now[1] + Vec3(0, 60, 0);
  EXPECT_FALSE(on_track.rejects(1));  // where its velocity took it: the marker being followed

  now[1] += Vec3(0, 0, 45);  // off its track by more than eps2 plus a frame's travel
  LabelFixture off_track(now);
  off_track.expectation.position[1] = now[1] + Vec3(0, 60, 0);
  EXPECT_TRUE(off_track.rejects(1));
}

TEST(LabelCheck, WithNoEstimateOfItsOwnItsTrackDecides) {
  std::vector<Vec3> now = line_at(20);
  LabelFixture on_track(now);
  EXPECT_FALSE(on_track.rejects(1));
  now[1] += Vec3(0, 0, 45);
  LabelFixture off_track(now);
  EXPECT_TRUE(off_track.rejects(1));
}

TEST(LabelCheck, AConfidentMissWithinEps2IsRejectedOnlyWhenAnotherExplainsIt) {
  // 10 mm from its own estimate, within eps2, but 5 standard deviations of a 2 mm claim.
  LabelFixture fx(line_at(20));
  fx.expectation.position[1] = fx.points[1] + Vec3(0, 10, 0);
  fx.expectation.variance[1] = 4.0;
  EXPECT_FALSE(fx.rejects(1));
  fx.missing_expected_at(3, fx.points[1] + Vec3(0, 4, 0));
  EXPECT_TRUE(fx.rejects(1));
}

TEST(LabelCheck, FindingAndJudgingAllocateNothing) {
  std::vector<Vec3> now = line_at(20);
  now[1] += Vec3(0, 0, 45);
  LabelFixture fx(now);
  fx.expectation.position[1] = now[1] + Vec3(0, 60, 0);
  test::CountAllocations allocations;
  fx.check.find_suspects(fx.points, fx.observed, fx.eps2, fx.tracks);
  const bool rejected = fx.rejects(1);
  EXPECT_EQ(allocations.count(), 0u);
  EXPECT_EQ(fx.check.suspects().size(), 1u);
  EXPECT_TRUE(rejected);
}

}  // namespace
}  // namespace skinstream
