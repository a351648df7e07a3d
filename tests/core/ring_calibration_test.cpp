#include "core/ring_calibration.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/offline/subject_builder.h"
#include "support/allocation_counter.h"
#include "support/synthetic_limb.h"

namespace skinstream {
namespace {

constexpr int kCheckedMarker = 3 * 8 + 2;  // a marker in the middle of the limb

struct LimbRings {
  LimbRings()
      : truth(test::make_limb_capture(options)), model(build_subject(truth, {})), single_gaps(model) {}
  test::LimbOptions options;
  Capture truth;
  SubjectModel model;
  SingleGapReconstruction single_gaps;

  std::vector<Vec3> frame(const Capture& c, int f) const {
    std::vector<Vec3> positions(c.point_count());
    for (int p = 0; p < c.point_count(); ++p) positions[p] = c.at(f, p);
    return positions;
  }
  // `loose` slid on the skin after training: 25 mm back and forth at 0.9 Hz.
  Capture with_loose_marker(int loose) const {
    Capture live = truth;
    for (int f = 0; f < live.frame_count; ++f)
      live.positions[f * live.point_count() + loose] +=
          Vec3(0, 0, 25.0 * std::sin(2.0 * M_PI * 0.9 * f / options.rate));
    return live;
  }
  bool ring_reads(int j, int marker) const {
    const auto first = model.ring.begin() + model.ring_offsets[j],
               last = model.ring.begin() + model.ring_offsets[j + 1];
    return j == marker || std::find(first, last, marker) != last;
  }
};

void check_each_frame(LimbRings& fx, RingCalibration& calibration, const Capture& c,
                      const std::vector<MarkerStatus>& status) {
  for (int f = 0; f < c.frame_count; ++f) calibration.check(fx.frame(c, f), status, fx.single_gaps);
}

TEST(RingCalibration, StartsAtTheOfflineCalibration) {
  LimbRings fx;
  RingCalibration calibration(fx.model, fx.options.rate);
  for (size_t k = 0; k < fx.model.ring.size(); ++k) EXPECT_EQ(calibration.ring(static_cast<int>(k)), 1.0);
  for (int i = 0; i < fx.model.marker_count(); ++i) EXPECT_EQ(calibration.rigid(i), 1.0);
}

// A marker that slides on the skin makes every opinion of or by it miss more than it claims:
// those climb well above 1, while the rings that do not read it, and every ring on the take it
// was trained on, stay near 1.
TEST(RingCalibration, AnOpinionThatMissesMoreClaimsLess) {
  LimbRings fx;
  const int loose = fx.model.ring[fx.model.ring_offsets[kCheckedMarker]];
  const std::vector<MarkerStatus> measured(fx.model.marker_count(), MarkerStatus::Measured);
  RingCalibration live(fx.model, fx.options.rate), clean(fx.model, fx.options.rate);
  check_each_frame(fx, live, fx.with_loose_marker(loose), measured);
  check_each_frame(fx, clean, fx.truth, measured);
  double about_loose = 1e300, others = 0.0, on_training = 0.0;
  for (int j = 0; j < fx.model.marker_count(); ++j)
    for (int k = fx.model.ring_offsets[j]; k < fx.model.ring_offsets[j + 1]; ++k) {
      if (j == loose || fx.model.ring[k] == loose)
        about_loose = std::min(about_loose, live.ring(k));
      else if (!fx.ring_reads(j, loose))
        others = std::max(others, live.ring(k));
      on_training = std::max(on_training, clean.ring(k));
    }
  EXPECT_GT(about_loose, 4.0);
  EXPECT_LT(others, 1.5);
  EXPECT_LT(on_training, 1.5);
  EXPECT_GT(live.rigid(loose), 4.0);  // eq. 2 of the loose marker from its ring
  EXPECT_LT(clean.rigid(loose), 1.5);
  EXPECT_GE(clean.rigid(loose), 1.0);
}

// Only a ring measured whole, with its marker, is checked: one with a member filled or relabelled
// keeps its calibration.
TEST(RingCalibration, ChecksOnlyRingsMeasuredWhole) {
  LimbRings fx;
  const int loose = fx.model.ring[fx.model.ring_offsets[kCheckedMarker]];
  std::vector<MarkerStatus> status(fx.model.marker_count(), MarkerStatus::Measured);
  status[loose] = MarkerStatus::Relabelled;
  RingCalibration calibration(fx.model, fx.options.rate);
  check_each_frame(fx, calibration, fx.with_loose_marker(loose), status);
  for (int j = 0; j < fx.model.marker_count(); ++j) {
    if (!fx.ring_reads(j, loose)) continue;
    for (int k = fx.model.ring_offsets[j]; k < fx.model.ring_offsets[j + 1]; ++k)
      EXPECT_EQ(calibration.ring(k), 1.0);
    EXPECT_EQ(calibration.rigid(j), 1.0);
  }
}

TEST(RingCalibration, ResetForgetsWhatItLearned) {
  LimbRings fx;
  const int loose = fx.model.ring[fx.model.ring_offsets[kCheckedMarker]];
  const std::vector<MarkerStatus> measured(fx.model.marker_count(), MarkerStatus::Measured);
  RingCalibration calibration(fx.model, fx.options.rate);
  check_each_frame(fx, calibration, fx.with_loose_marker(loose), measured);
  ASSERT_GT(calibration.rigid(loose), 1.0);
  calibration.reset();
  for (size_t k = 0; k < fx.model.ring.size(); ++k) EXPECT_EQ(calibration.ring(static_cast<int>(k)), 1.0);
  EXPECT_EQ(calibration.rigid(loose), 1.0);
  // And learns again as a new one does.
  RingCalibration fresh(fx.model, fx.options.rate);
  check_each_frame(fx, calibration, fx.truth, measured);
  check_each_frame(fx, fresh, fx.truth, measured);
  for (size_t k = 0; k < fx.model.ring.size(); ++k)
    EXPECT_EQ(calibration.ring(static_cast<int>(k)), fresh.ring(static_cast<int>(k)));
}

TEST(RingCalibration, AllocatesNothingPerFrame) {
  LimbRings fx;
  const std::vector<MarkerStatus> measured(fx.model.marker_count(), MarkerStatus::Measured);
  RingCalibration calibration(fx.model, fx.options.rate);
  std::vector<std::vector<Vec3>> frames;
  for (int f = 0; f < 100; ++f) frames.push_back(fx.frame(fx.truth, f));
  test::CountAllocations counter;
  for (const std::vector<Vec3>& positions : frames) calibration.check(positions, measured, fx.single_gaps);
  EXPECT_EQ(counter.count(), 0u);
}

}  // namespace
}  // namespace skinstream
