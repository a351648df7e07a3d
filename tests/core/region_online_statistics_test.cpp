#include "core/region_online_statistics.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>

#include "core/offline/region_pca_trainer.h"
#include "core/region_pca_fit.h"
#include "support/allocation_counter.h"

namespace skinstream {
namespace {

// A leg: four thigh markers, four shank markers and a foot of three (toe first), the knee at
// 500 mm. The training take stands still (the knee straight, the whole leg turning and moving a
// little); what follows bends the knee by up to 34 degrees, which training never showed.
constexpr int kLegMarkers = 11;
constexpr double kRate = 120.0;

std::vector<Vec3> leg_pose(double knee, double turn, const Vec3& shift) {
  const std::vector<Vec3> thigh = {{60, 0, 850}, {-55, 10, 800}, {0, 70, 700}, {50, -40, 600}};
  const std::vector<Vec3> below = {{45, 30, 420}, {-50, 20, 350}, {0, 60, 250}, {40, -30, 150},  // shank
                                   {0, 180, 40}, {-45, 120, 45}, {0, -60, 60}};                    // toe, metatarsal, heel
  const Vec3 knee_centre(0, 0, 500);
  const Eigen::Matrix3d bend = Eigen::AngleAxisd(knee, Vec3::UnitX()).toRotationMatrix();
  const Eigen::Matrix3d whole = Eigen::AngleAxisd(turn, Vec3::UnitZ()).toRotationMatrix();
  std::vector<Vec3> pose(kLegMarkers);
  for (int k = 0; k < 3; ++k) pose[k] = whole * (knee_centre + bend * (below[4 + k] - knee_centre)) + shift;
  for (int k = 0; k < 4; ++k) pose[3 + k] = whole * (knee_centre + bend * (below[k] - knee_centre)) + shift;
  for (int k = 0; k < 4; ++k) pose[7 + k] = whole * thigh[k] + shift;
  return pose;
}

std::vector<Vec3> noisy(std::vector<Vec3> pose, std::mt19937& rng) {
  std::normal_distribution<double> noise(0.0, 0.5);
  for (Vec3& p : pose) p += Vec3(noise(rng), noise(rng), noise(rng));
  return pose;
}

// The bending take at frame f: the knee through +-34 degrees every 2 s while the leg turns.
std::vector<Vec3> bending(int f) {
  const double t = f / kRate;
  return leg_pose(0.6 * std::sin(M_PI * t), 0.3 * std::sin(0.4 * t), Vec3(100 * std::sin(0.3 * t), 0, 0));
}

// Every marker's region is the whole leg with the marker first; each trained on the still take.
SubjectModel standing_leg() {
  std::vector<std::string> labels;
  for (int m = 0; m < kLegMarkers; ++m) labels.push_back("M" + std::to_string(m));
  Capture still(labels, 600, kRate);
  std::mt19937 rng(7);
  for (int f = 0; f < still.frame_count; ++f) {
    const std::vector<Vec3> pose = noisy(leg_pose(0.0, 0.2 * std::sin(0.01 * f), Vec3(0.2 * f, 0, 0)), rng);
    for (int m = 0; m < kLegMarkers; ++m) still.at(f, m) = pose[m];
  }
  SubjectModel model;
  model.marker_names = labels;
  model.region_offsets.push_back(0);
  for (int i = 0; i < kLegMarkers; ++i) {
    std::vector<int> members = {i};
    for (int m = 0; m < kLegMarkers; ++m)
      if (m != i) members.push_back(m);
    model.region.insert(model.region.end(), members.begin(), members.end());
    model.region_offsets.push_back(static_cast<int>(model.region.size()));
    model.region_pca.push_back(train_region_pca(still, members));
  }
  return model;
}

struct Toe {
  double error = 0.0;     // mm
  double variance = 0.0;  // claimed, per coordinate (mm^2)
};

// The toe estimated with the whole foot hidden (the thigh and shank seen), at knee angle `knee`.
Toe toe_in_a_gap(RegionPcaFit& fit, const RegionShapeGaussian& shape, double knee) {
  const std::vector<Vec3> pose = leg_pose(knee, 0.1, Vec3(30, -20, 0));
  const std::vector<char> observed = {0, 0, 0, 1, 1, 1, 1, 1, 1, 1, 1};
  Toe toe;
  Vec3 estimate;
  EXPECT_TRUE(fit.estimate(shape, pose, observed, estimate, toe.variance));
  toe.error = (estimate - pose[0]).norm();
  return toe;
}

void learn_frames(RegionOnlineStatistics& statistics, int first, int count) {
  const std::vector<MarkerStatus> measured(kLegMarkers, MarkerStatus::Measured);
  for (int f = first; f < first + count; ++f) statistics.learn(bending(f), measured);
}

TEST(RegionOnlineStatistics, UntilItLearnsTheBlendIsTheOfflineModel) {
  const SubjectModel model = standing_leg();
  RegionOnlineStatistics statistics(model);
  RegionShapeGaussian offline;
  region_gaussian_from_pca(model.region_pca[0], offline);
  const RegionShapeGaussian& blend = statistics.blended(0);
  EXPECT_EQ(blend.mean, offline.mean);
  EXPECT_EQ(blend.covariance, offline.covariance);
  EXPECT_EQ(blend.calibration, offline.calibration);
  EXPECT_EQ(statistics.evidence_seconds(0), 0.0);
}

// A region learns only from frames in which all of its members were measured.
TEST(RegionOnlineStatistics, LearnsOnlyFromRegionsMeasuredWhole) {
  const SubjectModel model = standing_leg();
  RegionOnlineStatistics statistics(model);
  std::vector<MarkerStatus> status(kLegMarkers, MarkerStatus::Measured);
  status[5] = MarkerStatus::FilledPca;
  for (int f = 0; f < 240; ++f) statistics.learn(bending(f), status);
  for (int i = 0; i < kLegMarkers; ++i) EXPECT_EQ(statistics.evidence_seconds(i), 0.0) << "region " << i;
  status[5] = MarkerStatus::Measured;
  for (int f = 0; f < 240; ++f) statistics.learn(bending(f), status);
  for (int i = 0; i < kLegMarkers; ++i) EXPECT_GT(statistics.evidence_seconds(i), 1.0) << "region " << i;
}

// The offline model never saw the knee bend: with the foot hidden it puts the toe where a straight
// leg would have it. After 20 s of the bending take seen whole, the blend reads the foot from the
// shank. The poses estimated are not among those learned from (another turn and place, angles
// between the learned frames').
TEST(RegionOnlineStatistics, LearnsAMotionTheOfflineTrainingNeverSaw) {
  const SubjectModel model = standing_leg();
  RegionOnlineStatistics statistics(model);
  RegionPcaFit fit;
  learn_frames(statistics, 0, static_cast<int>(20 * kRate));
  EXPECT_GT(statistics.evidence_seconds(0), 10.0);
  RegionShapeGaussian offline;
  region_gaussian_from_pca(model.region_pca[0], offline);
  double offline_error = 0.0, online_error = 0.0;
  const int trials = 9;
  for (int t = 0; t < trials; ++t) {
    const double knee = -0.5 + 0.123 * t;
    offline_error += toe_in_a_gap(fit, offline, knee).error / trials;
    online_error += toe_in_a_gap(fit, statistics.blended(0), knee).error / trials;
  }
  // Measured when written: offline 43.8 mm, online 4.9 mm.
  EXPECT_LT(online_error, 8.0);
  EXPECT_GT(offline_error, 3.0 * 8.0);
}

// A blend that has seen little must not claim much: from a few frames its covariance knows a
// few directions and would condition on them with confidence; its prequential calibration says
// how far to trust it. Its squared miss stays within 9 claimed variances (3 standard deviations
// per coordinate). Measured when written (miss, claimed standard deviation): after 8 frames
// 41.6 mm, 21.2 mm (5.4 mm without the online calibration); 40: 15.5, 8.3 (2.2); 400: 12.6, 7.4;
// 2400: 8.0, 4.8. (The offline model alone misses by 75.6 mm claiming 9.4 mm: a knee bend it never
// saw, which its novelty factor only partly reveals.)
TEST(RegionOnlineStatistics, ItsClaimCoversItsMiss) {
  const SubjectModel model = standing_leg();
  RegionPcaFit fit;
  for (int seen : {8, 40, 400, 2400}) {
    RegionOnlineStatistics learner(model);
    learn_frames(learner, 0, seen);
    const Toe toe = toe_in_a_gap(fit, learner.blended(0), 0.45);
    EXPECT_LE(toe.error * toe.error / 3.0, 9.0 * toe.variance) << "after " << seen << " frames";
  }
}

TEST(RegionOnlineStatistics, AllocatesNothingPerFrame) {
  const SubjectModel model = standing_leg();
  RegionOnlineStatistics statistics(model);
  RegionPcaFit fit;
  const std::vector<MarkerStatus> measured(kLegMarkers, MarkerStatus::Measured);
  std::vector<std::vector<Vec3>> poses;
  for (int f = 0; f < 200; ++f) poses.push_back(bending(f));
  const std::vector<char> observed = {0, 0, 0, 1, 1, 1, 1, 1, 1, 1, 1};
  test::CountAllocations counter;
  for (int f = 0; f < 200; ++f) {
    statistics.learn(poses[f], measured);
    Vec3 estimate;
    double variance = 0.0;
    fit.estimate(statistics.blended(f % kLegMarkers), poses[f], observed, estimate, variance);
    statistics.calibration(f % kLegMarkers);
  }
  EXPECT_EQ(counter.count(), 0u);
}

}  // namespace
}  // namespace skinstream
