#include "core/local_smoothing.h"

#include <gtest/gtest.h>

#include <random>

#include "core/capture_filler.h"
#include "core/offline/subject_builder.h"
#include "support/allocation_counter.h"
#include "support/synthetic_limb.h"

namespace skinstream {
namespace {

double rms_error(const Capture& a, const Capture& b) {
  double sum = 0;
  for (size_t k = 0; k < a.positions.size(); ++k) sum += (a.positions[k] - b.positions[k]).squaredNorm();
  return std::sqrt(sum / a.positions.size());
}

Capture noisy(const Capture& truth, double sigma) {
  Capture c = truth;
  std::mt19937_64 rng(42);
  std::normal_distribution<double> g(0.0, sigma);
  for (Vec3& p : c.positions) p += Vec3(g(rng), g(rng), g(rng));
  return c;
}

TEST(LocalSmoothing, OfflineLeavesSmoothMotionAloneAndRemovesNoise) {
  const Capture truth = test::make_limb_capture();
  const SubjectModel model = build_subject(truth, {});
  Capture clean = truth;
  smooth_offline(model, clean.positions, clean.frame_count, {});
  EXPECT_LT(rms_error(clean, truth), 0.05);  // fast rigid motion is not smoothed away

  const Capture with_noise = noisy(truth, 1.0);
  Capture smoothed = with_noise;
  smooth_offline(model, smoothed.positions, smoothed.frame_count, {});
  EXPECT_LT(rms_error(smoothed, truth), 0.7 * rms_error(with_noise, truth));
}

TEST(LocalSmoothing, OnlineWithLookaheadRemovesNoiseAndKeepsFrameOrder) {
  const Capture truth = test::make_limb_capture();
  const SubjectModel model = build_subject(truth, {});
  const Capture with_noise = noisy(truth, 1.0);
  CaptureFillOptions o;
  o.smoothing = SmoothingMode::Online;
  o.smoothing_options.lookahead = 2;
  const Capture smoothed = fill_capture(model, with_noise, o);
  EXPECT_LT(rms_error(smoothed, truth), 0.8 * rms_error(with_noise, truth));
}

TEST(LocalSmoothing, OnlineReleasesEachFrameOnce) {
  const Capture truth = test::make_limb_capture();
  const SubjectModel model = build_subject(truth, {});
  SmoothingOptions o;
  o.lookahead = 3;
  OnlineSmoother smoother(model, o);
  const int n = model.marker_count();
  std::vector<Vec3> in(n), out(n);
  std::vector<MarkerStatus> status(n, MarkerStatus::Measured), out_status(n);
  std::vector<long> released;
  for (int f = 0; f < 20; ++f) {
    for (int i = 0; i < n; ++i) in[i] = truth.at(f, i);
    long r;
    if (smoother.push(in, status, f, {out, out_status}, r)) released.push_back(r);
  }
  long r;
  while (smoother.drain({out, out_status}, r)) released.push_back(r);
  ASSERT_EQ(released.size(), 20u);
  for (int f = 0; f < 20; ++f) EXPECT_EQ(released[f], f);
}

TEST(LocalSmoothing, OnlineAllocatesNothingPerFrame) {
  const Capture truth = test::make_limb_capture();
  const SubjectModel model = build_subject(truth, {});
  OnlineSmoother smoother(model, {});
  const int n = model.marker_count();
  std::vector<Vec3> in(n), out(n);
  std::vector<MarkerStatus> status(n, MarkerStatus::Measured), out_status(n);
  test::CountAllocations counter;
  for (int f = 0; f < 50; ++f) {
    for (int i = 0; i < n; ++i) in[i] = truth.at(f, i);
    long released;
    smoother.push(in, status, f, {out, out_status}, released);
  }
  EXPECT_EQ(counter.count(), 0u);
}

}  // namespace
}  // namespace skinstream
