#include "core/marker_tracks.h"

#include <gtest/gtest.h>

#include <vector>

#include "support/allocation_counter.h"

namespace skinstream {
namespace {

using S = MarkerStatus;

TEST(MarkerTracks, NoTrackBeforeTheFirstFrame) {
  const MarkerTracks tracks(2);
  EXPECT_FALSE(tracks.has_last());
  EXPECT_FALSE(tracks.measured_last_two_frames(0));
  EXPECT_EQ(tracks.last_status(0), S::Held);
  EXPECT_FALSE(tracks.off_track(0, Vec3(1e6, 0, 0), 1.0));
}

TEST(MarkerTracks, AMarkerMeasuredTwiceMovesOnAtItsVelocity) {
  MarkerTracks tracks(2);
  const std::vector<S> measured = {S::Measured, S::Relabelled};
  tracks.advance(std::vector<Vec3>{Vec3(0, 0, 0), Vec3(5, 0, 0)}, measured);
  EXPECT_TRUE(tracks.has_last());
  EXPECT_FALSE(tracks.measured_last_two_frames(0));  // one frame: no velocity yet
  EXPECT_EQ(tracks.prediction(0), Vec3(0, 0, 0));
  tracks.advance(std::vector<Vec3>{Vec3(10, 0, 0), Vec3(5, 2, 0)}, measured);
  ASSERT_TRUE(tracks.measured_last_two_frames(0));
  EXPECT_EQ(tracks.prediction(0), Vec3(20, 0, 0));
  EXPECT_EQ(tracks.prediction(1), Vec3(5, 4, 0));
  // Off its track beyond the tolerance plus a frame's travel (10 mm), not within it.
  EXPECT_FALSE(tracks.off_track(0, Vec3(20, 14.9, 0), 5.0));
  EXPECT_TRUE(tracks.off_track(0, Vec3(20, 15.1, 0), 5.0));
}

TEST(MarkerTracks, AnEstimateInEitherOfTheLastTwoFramesGivesNoVelocity) {
  MarkerTracks tracks(2);
  tracks.advance(std::vector<Vec3>{Vec3(0, 0, 0), Vec3(0, 0, 0)}, std::vector<S>{S::FilledPca, S::Measured});
  tracks.advance(std::vector<Vec3>{Vec3(10, 0, 0), Vec3(10, 0, 0)},
                 std::vector<S>{S::Measured, S::FilledRigid});
  for (int i : {0, 1}) {
    EXPECT_FALSE(tracks.measured_last_two_frames(i)) << i;
    EXPECT_EQ(tracks.prediction(i), Vec3(10, 0, 0)) << i;  // where it was last
    EXPECT_FALSE(tracks.off_track(i, Vec3(1e6, 0, 0), 1.0)) << i;
  }
}

TEST(MarkerTracks, ARevokedRelabelLeavesAnEstimateBehind) {
  MarkerTracks tracks(1);
  const std::vector<S> relabelled = {S::Relabelled};
  tracks.advance(std::vector<Vec3>{Vec3(0, 0, 0)}, relabelled);
  tracks.advance(std::vector<Vec3>{Vec3(1, 0, 0)}, relabelled);
  ASSERT_TRUE(tracks.measured_last_two_frames(0));
  tracks.take_last_as_estimated(0);
  EXPECT_EQ(tracks.last_status(0), S::FilledRigid);
  EXPECT_FALSE(tracks.measured_last_two_frames(0));
  tracks.advance(std::vector<Vec3>{Vec3(2, 0, 0)}, std::vector<S>{S::Measured});
  EXPECT_FALSE(tracks.measured_last_two_frames(0));  // the frame before is an estimate now
}

TEST(MarkerTracks, ResetForgetsEveryTrack) {
  MarkerTracks tracks(1);
  const std::vector<S> measured = {S::Measured};
  tracks.advance(std::vector<Vec3>{Vec3(0, 0, 0)}, measured);
  tracks.advance(std::vector<Vec3>{Vec3(1, 0, 0)}, measured);
  tracks.reset();
  EXPECT_FALSE(tracks.has_last());
  EXPECT_FALSE(tracks.measured_last_two_frames(0));
  tracks.advance(std::vector<Vec3>{Vec3(7, 0, 0)}, measured);
  EXPECT_FALSE(tracks.measured_last_two_frames(0));  // the frame before the reset is not a velocity
}

TEST(MarkerTracks, AdvancingAllocatesNothing) {
  MarkerTracks tracks(300);
  const std::vector<Vec3> positions(300, Vec3(1, 2, 3));
  const std::vector<S> status(300, S::Measured);
  tracks.advance(positions, status);
  test::CountAllocations counter;
  for (int f = 0; f < 100; ++f) tracks.advance(positions, status);
  EXPECT_EQ(counter.count(), 0u);
}

}  // namespace
}  // namespace skinstream
