#pragma once
// What the regions (region_pca_fit.h) learn while the filler runs (beyond the paper). The
// offline models know only the training take: a subject who stood still there and walks now has
// feet whose regions never saw a step, while every frame in which a region is seen whole shows
// how it moves now. From such frames each region keeps a running mean and covariance of its
// aligned shape (aligned to the offline mean, so both live in one frame), forgetting with a
// time constant, and its shape Gaussian becomes a blend of the offline model and these, weighed
// by evidence (seconds seen against the seconds the offline model is worth):
//   mean = (1 - w) mean_offline + w mean_online
//   covariance = (1 - w) C_offline + w C_online + w (1 - w) d d^T   (d: the means' difference)
// The residual stays the offline model's. A covariance from few frames still claims too much in
// the few directions it has seen, so the calibration is learned too, prequentially: before a frame
// is learned from, the blend as it stands estimates member 0 with members 0-2 left out (as the
// offline calibration does), and the recent miss over the variance claimed is the online
// calibration. The blend's calibration moves from the offline one to it with the evidence, and
// is never below it: a region claims no more than it has lately been shown to deserve.
//
// Cost is bounded per frame: at most `updates_per_frame` regions learn, in turn. Everything is
// sized in the constructor; learn() and blended() allocate nothing. Deterministic.

#include <array>
#include <span>
#include <vector>

#include "core/marker_status.h"
#include "core/recent_miss.h"
#include "core/region_pca_fit.h"
#include "core/region_shape_gaussian.h"
#include "core/subject_model.h"

namespace skinstream {

struct RegionLearningOptions {
  double rate_hz = 120.0;
  int updates_per_frame = 2;     // regions that learn from one frame (round robin)
  double memory_seconds = 60.0;  // what was seen that long ago weighs 1/e
  double prior_seconds = 10.0;   // the offline model counts as this much evidence
  double calibration_memory_seconds = 10.0;  // the prequential calibration forgets faster
};

class RegionOnlineStatistics {
 public:
  RegionOnlineStatistics(const SubjectModel& model, const RegionLearningOptions& options = {});

  // After a frame: regions whose members were all measured in it learn from it (`positions`,
  // `status`: one per subject marker).
  void learn(std::span<const Vec3> positions, std::span<const MarkerStatus> status);
  // Marker i's region as known now (offline model alone until it learned something). The
  // reference stays valid until the next call.
  const RegionShapeGaussian& blended(int i);
  // Member 0's calibration in the blend, without forming it.
  double calibration(int i) const;
  // Changes whenever region i learns (what a RegionSolve kept for it depends on).
  long version(int i) const { return regions_[i].updates; }
  // Seconds of evidence region i learned from, after forgetting.
  double evidence_seconds(int i) const { return regions_[i].evidence; }
  void reset();

 private:
  struct Region {
    int first = 0;         // offset of its members in model.region
    int size = 0;
    size_t mean_at = 0;    // 3 * size values in offline_mean_ and online_mean_
    size_t matrix_at = 0;  // 9 * size^2 values (column-major) in offline_covariance_ and scatter_
    double evidence = 0.0;  // seconds
    long learned_frame = -1;  // the frame it last learned from
    long updates = 0;
    RecentMiss recent{};  // the prequential calibration's sums, forgetting too
  };
  double weight(const Region& r) const { return r.evidence / (r.evidence + options_.prior_seconds); }
  void learn_region(int i, std::span<const Vec3> positions);

  const SubjectModel& model_;
  RegionLearningOptions options_;
  long nominal_frames_ = 1;  // between a region's updates when every region is seen: the most one stands for
  long frame_ = 0;
  int cursor_ = 0;
  std::vector<Region> regions_;
  std::vector<double> offline_mean_, online_mean_;
  std::vector<double> offline_covariance_, scatter_;  // scatter_: the online covariance times evidence
  RegionShapeGaussian blend_;
  RegionPcaFit fit_;
  std::array<Vec3, SubjectModel::kMaxRing> shape_, reference_;
  std::array<char, SubjectModel::kMaxRing> left_out_;
  PcaVector aligned_;
};

}  // namespace skinstream
