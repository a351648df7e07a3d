#include "core/offline/region_pca_trainer.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <set>

#include "core/absolute_orientation.h"
#include "core/offline/marker_distance_stats.h"
#include "core/region_pca_fit.h"

namespace skinstream {
namespace {

// Two legs walking: each leg a shin, an ankle, a heel, a toe and a fifth metatarsal marker. The
// legs swing forward and back in opposite phase (200 mm), and each foot pitches about its ankle
// with the gait (15 degrees). The feet are 120 mm apart side by side, nearer each other than to
// their own shins (380 mm above).
enum Marker { kLShin, kLAnkle, kLHeel, kLToe, kLMeta, kRShin, kRAnkle, kRHeel, kRToe, kRMeta, kMarkers };

std::vector<Vec3> walking_pose(double phase) {
  std::vector<Vec3> pose(kMarkers);
  for (int side = 0; side < 2; ++side) {
    const double x = side == 0 ? -60.0 : 60.0, swing = (side == 0 ? 1.0 : -1.0) * std::sin(phase);
    const Vec3 ankle(x, 200.0 * swing, 80.0);
    const Eigen::Matrix3d pitch = Eigen::AngleAxisd(0.26 * swing, Vec3::UnitX()).toRotationMatrix();
    const int first = side == 0 ? kLShin : kRShin;
    pose[first + 0] = ankle + Vec3(0, 0, 380);
    pose[first + 1] = ankle;
    pose[first + 2] = ankle + pitch * Vec3(0, -60, -50);
    pose[first + 3] = ankle + pitch * Vec3(0, 150, -60);
    pose[first + 4] = ankle + pitch * Vec3(side == 0 ? -40 : 40, 110, -60);
  }
  return pose;
}

Capture walking_capture(int frames, double phase_step) {
  std::vector<std::string> labels;
  for (int m = 0; m < kMarkers; ++m) labels.push_back("M" + std::to_string(m));
  Capture c(labels, frames, 120.0);
  for (int f = 0; f < frames; ++f) {
    const std::vector<Vec3> pose = walking_pose(0.3 + phase_step * f);
    for (int m = 0; m < kMarkers; ++m) c.at(f, m) = pose[m];
  }
  return c;
}

std::vector<int> all_markers() {
  std::vector<int> v(kMarkers);
  for (int m = 0; m < kMarkers; ++m) v[m] = m;
  return v;
}

TEST(MarkerRegion, StartsWithTheMarkerAndHoldsAtMostSize) {
  Eigen::MatrixXd skin(3, 3);
  skin << 0, 5, 1, 5, 0, std::numeric_limits<double>::infinity(), 1, std::numeric_limits<double>::infinity(), 0;
  EXPECT_EQ(marker_region(skin, 0, 12), (std::vector<int>{0, 2, 1}));
  EXPECT_EQ(marker_region(skin, 0, 2), (std::vector<int>{0, 2}));
  EXPECT_EQ(marker_region(skin, 1, 12), (std::vector<int>{1, 0}));  // never seen with marker 2
}

// The other foot is nearer in the pose, but its distance changes with every step: a foot marker's
// region is its own leg, never the other foot's markers before all of its own.
TEST(MarkerRegion, AFootMarkersRegionIsItsOwnLegNotTheOtherFoot) {
  const Capture take = walking_capture(600, 0.05);
  const std::vector<Vec3> pose = walking_pose(0.0);
  ASSERT_LT((pose[kLToe] - pose[kRToe]).norm(), (pose[kLToe] - pose[kLShin]).norm());  // proximity alone would mix the feet
  const Eigen::MatrixXd skin = compute_marker_distance_stats(take, all_markers()).skin_distance();
  for (int m : {kLAnkle, kLHeel, kLToe, kLMeta}) {
    const std::vector<int> region = marker_region(skin, m, 5);
    EXPECT_EQ(std::set<int>(region.begin(), region.end()), (std::set<int>{kLShin, kLAnkle, kLHeel, kLToe, kLMeta})) << "marker " << m;
  }
  for (int m : {kRAnkle, kRHeel, kRToe, kRMeta}) {
    const std::vector<int> region = marker_region(skin, m, 5);
    EXPECT_EQ(std::set<int>(region.begin(), region.end()), (std::set<int>{kRShin, kRAnkle, kRHeel, kRToe, kRMeta})) << "marker " << m;
  }
}

// Three of the left foot's four markers gone: the region (both legs) still reads the foot's pitch
// from the gait, on poses between those of training, where the foot carried rigidly with what is
// left of its leg (ankle and shin) misses by the pitch. (The 99% of variance kept leaves out part
// of the pitch's curve: 5.6 mm remain.)
TEST(RegionPcaFit, EstimatesAFootWithMostOfItsNeighbourhoodGone) {
  const Capture training = walking_capture(900, 0.037);
  const std::vector<int> region = {kLToe, kLMeta, kLHeel, kLAnkle, kLShin, kRShin, kRAnkle, kRHeel, kRToe, kRMeta};
  const MarkerPcaModel model = train_region_pca(training, region);
  ASSERT_GT(model.training_frames, 0);
  EXPECT_GE(model.slot_calibration(0), 1.0);

  RegionPcaFit fit;
  std::vector<char> observed(region.size(), 1);
  observed[0] = observed[1] = observed[2] = 0;  // toe, metatarsal, heel
  const std::vector<Vec3> rest = walking_pose(0.0);
  double region_error = 0.0, rigid_error = 0.0;
  const int trials = 50;
  for (int t = 0; t < trials; ++t) {
    const std::vector<Vec3> pose = walking_pose(0.011 + 0.123 * t);
    std::vector<Vec3> members;
    for (int m : region) members.push_back(pose[m]);
    Vec3 estimate;
    double variance = 0.0;
    ASSERT_TRUE(fit.estimate(model, members, observed, estimate, variance));
    EXPECT_GT(variance, 0.0);
    region_error += (estimate - pose[kLToe]).norm() / trials;
    // The toe carried with the ankle and shin and the left leg's pose at rest (no pitch known).
    RigidTransform carry;
    const std::vector<Vec3> from = {rest[kLAnkle], rest[kLShin], rest[kLAnkle] + Vec3(1, 0, 0)};
    const std::vector<Vec3> to = {pose[kLAnkle], pose[kLShin], pose[kLAnkle] + Vec3(1, 0, 0)};
    fit_rigid(from, to, carry);
    rigid_error += (carry.apply(rest[kLToe]) - pose[kLToe]).norm() / trials;
  }
  // Measured when written: 5.6 mm against 27.2 mm (one round of alignment instead of alternating
  // to convergence: 33.7 mm).
  EXPECT_LT(region_error, 8.0);
  EXPECT_GT(rigid_error, 3.0 * region_error);
}

// Whether the left foot's region (foot and shin), trained on `training`, estimates the toe in
// its first frame with the members `observed`.
bool estimates_the_toe(const Capture& training, const std::vector<char>& observed) {
  const std::vector<int> region = {kLToe, kLMeta, kLHeel, kLAnkle, kLShin};
  std::vector<Vec3> members;
  for (int m : region) members.push_back(training.at(0, m));
  RegionPcaFit fit;
  Vec3 estimate;
  double variance = 0.0;
  return fit.estimate(train_region_pca(training, region), members, observed, estimate, variance);
}

TEST(RegionPcaFit, NeedsThreeObservedMembers) {
  const Capture training = walking_capture(300, 0.05);
  EXPECT_FALSE(estimates_the_toe(training, {0, 0, 0, 1, 1}));
  EXPECT_TRUE(estimates_the_toe(training, {0, 0, 1, 1, 1}));
}

// Too few frames with the whole region present: an untrained model that never gives an opinion.
TEST(RegionPcaTrainer, TooFewCompleteFramesGiveNoOpinion) {
  const Capture training = walking_capture(20, 0.05);
  EXPECT_EQ(train_region_pca(training, {kLToe, kLMeta, kLHeel, kLAnkle, kLShin}).training_frames, 0);
  EXPECT_FALSE(estimates_the_toe(training, {0, 1, 1, 1, 1}));
}

}  // namespace
}  // namespace skinstream
