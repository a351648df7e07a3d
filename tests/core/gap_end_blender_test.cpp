#include "core/gap_end_blender.h"

#include <gtest/gtest.h>

#include "core/capture_filler.h"
#include "core/offline/subject_builder.h"
#include "support/allocation_counter.h"
#include "support/synthetic_limb.h"

namespace skinstream {
namespace {

constexpr int kMarker = 3 * 8 + 2;

double error_near_gap_end(int lookahead) {
  const Capture truth = test::make_limb_capture();
  const SubjectModel model = build_subject(truth, {});
  Capture gapped = truth;
  for (int f = 100; f < 300; ++f) gapped.at(f, kMarker) = missing_point();
  CaptureFillOptions o;
  o.lookahead = lookahead;
  const Capture filled = fill_capture(model, gapped, o);
  double sum = 0;
  for (int f = 290; f < 300; ++f) sum += (filled.at(f, kMarker) - truth.at(f, kMarker)).norm();
  return sum / 10;
}

TEST(GapEndBlender, LookaheadZeroPassesFramesThrough) {
  const Capture truth = test::make_limb_capture();
  const SubjectModel model = build_subject(truth, {});
  GapEndBlender blender(model, 0);
  const int n = model.marker_count();
  std::vector<Vec3> in(n), out(n);
  std::vector<MarkerStatus> status(n, MarkerStatus::Measured), out_status(n);
  for (int f = 0; f < 5; ++f) {
    for (int i = 0; i < n; ++i) in[i] = truth.at(f, i);
    long released = -1;
    ASSERT_TRUE(blender.push(in, status, f, {out, out_status}, released));
    EXPECT_EQ(released, f);
    EXPECT_EQ(out, in);
  }
  long released;
  EXPECT_FALSE(blender.drain({out, out_status}, released));
}

TEST(GapEndBlender, ReleasesEveryFrameOnceInOrderWithLookahead) {
  const Capture truth = test::make_limb_capture();
  const SubjectModel model = build_subject(truth, {});
  GapEndBlender blender(model, 4);
  const int n = model.marker_count();
  std::vector<Vec3> in(n), out(n);
  std::vector<MarkerStatus> status(n, MarkerStatus::Measured), out_status(n);
  std::vector<long> released_frames;
  for (int f = 0; f < 10; ++f) {
    for (int i = 0; i < n; ++i) in[i] = truth.at(f, i);
    long released;
    if (blender.push(in, status, f, {out, out_status}, released)) released_frames.push_back(released);
  }
  long released;
  while (blender.drain({out, out_status}, released)) released_frames.push_back(released);
  ASSERT_EQ(released_frames.size(), 10u);
  for (int f = 0; f < 10; ++f) EXPECT_EQ(released_frames[f], f);
}

TEST(GapEndBlender, LookaheadReducesErrorAtTheEndOfAGap) {
  const double causal = error_near_gap_end(0);
  const double blended = error_near_gap_end(8);
  EXPECT_LT(blended, causal);
}

TEST(GapEndBlender, AllocatesNothingPerFrame) {
  const Capture truth = test::make_limb_capture();
  const SubjectModel model = build_subject(truth, {});
  GapEndBlender blender(model, 6);
  const int n = model.marker_count();
  std::vector<Vec3> in(n), out(n);
  std::vector<MarkerStatus> status(n, MarkerStatus::Measured), out_status(n);
  test::CountAllocations counter;
  for (int f = 0; f < 100; ++f) {
    for (int i = 0; i < n; ++i) in[i] = truth.at(f, i);
    status[kMarker] = (f / 10) % 2 ? MarkerStatus::FilledPca : MarkerStatus::Measured;  // gaps end often
    long released;
    blender.push(in, status, f, {out, out_status}, released);
  }
  EXPECT_EQ(counter.count(), 0u);
}

}  // namespace
}  // namespace skinstream
