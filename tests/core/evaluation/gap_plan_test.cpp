#include "core/evaluation/gap_plan.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>

namespace skinstream {
namespace {

// `markers` labelled channels plus one unlabelled, all present, 120 Hz.
Capture full_capture(int markers, int frames, double rate = 120.0) {
  std::vector<std::string> labels;
  for (int p = 0; p < markers; ++p) labels.push_back("thigh_" + std::to_string(p));
  labels.push_back("*1");
  Capture capture(labels, frames, rate);
  for (int f = 0; f < frames; ++f)
    for (int p = 0; p < capture.point_count(); ++p) capture.at(f, p) = Vec3(p, f, 1.0);
  return capture;
}

TEST(GapPlan, RejectsInvalidOptions) {
  const Capture capture = full_capture(3, 600);
  EXPECT_THROW(plan_gaps(capture, {.min_frames = 0}), std::invalid_argument);
  EXPECT_THROW(plan_gaps(capture, {.max_seconds = 0.0}), std::invalid_argument);
  EXPECT_THROW(plan_gaps(capture, {.max_seconds = NAN}), std::invalid_argument);
  EXPECT_THROW(plan_gaps(capture, {.gaps_per_marker_per_minute = -1.0}), std::invalid_argument);
  EXPECT_THROW(plan_gaps(capture, {.gaps_per_marker_per_minute = INFINITY}), std::invalid_argument);
  EXPECT_THROW(plan_gaps(capture, {.margin_frames = -1}), std::invalid_argument);
  EXPECT_THROW(plan_gaps(capture, {.min_seconds = -1.0}), std::invalid_argument);
  EXPECT_THROW(plan_gaps(capture, {.fraction_of_samples = 0.6}), std::invalid_argument);
  EXPECT_THROW(plan_gaps(capture, {.fraction_of_samples = NAN}), std::invalid_argument);
  EXPECT_THROW(plan_gaps(capture, {.markers_per_gap = 0}), std::invalid_argument);
}

TEST(GapPlan, RejectsACaptureWithoutRateOrWithMismatchedPositions) {
  Capture no_rate = full_capture(3, 600);
  no_rate.rate_hz = 0.0;
  EXPECT_THROW(plan_gaps(no_rate, {}), std::invalid_argument);
  Capture broken = full_capture(3, 600);
  broken.positions.pop_back();
  EXPECT_THROW(plan_gaps(broken, {}), std::invalid_argument);
}

TEST(GapPlan, ApplyRejectsGapsOutsideTheCapture) {
  const Capture capture = full_capture(2, 100);
  EXPECT_THROW(apply_gaps(capture, {{0, 10, 0}}), std::invalid_argument);
  EXPECT_THROW(apply_gaps(capture, {{3, 10, 5}}), std::out_of_range);
  EXPECT_THROW(apply_gaps(capture, {{-1, 10, 5}}), std::out_of_range);
  EXPECT_THROW(apply_gaps(capture, {{0, -1, 5}}), std::out_of_range);
  EXPECT_THROW(apply_gaps(capture, {{0, 96, 5}}), std::out_of_range);
}

TEST(GapPlan, DeterministicPerSeedAndDifferentAcrossSeeds) {
  const Capture capture = full_capture(20, 4800);
  const auto same = [](const std::vector<Gap>& a, const std::vector<Gap>& b) {
    return std::equal(a.begin(), a.end(), b.begin(), b.end(), [](const Gap& x, const Gap& y) {
      return x.point == y.point && x.first_frame == y.first_frame && x.length == y.length;
    });
  };
  const std::vector<Gap> first = plan_gaps(capture, {.seed = 7});
  EXPECT_TRUE(same(first, plan_gaps(capture, {.seed = 7})));
  EXPECT_FALSE(same(first, plan_gaps(capture, {.seed = 8})));
}

TEST(GapPlan, MatchesRecordedPlanForSeedOne) {
  // Guards the platform independence: mt19937_64 plus our own conversions, no std:: distributions.
  const std::vector<Gap> plan = plan_gaps(full_capture(2, 1200), {.seed = 1});
  std::string text;
  for (const Gap& gap : plan)
    text += std::to_string(gap.point) + ":" + std::to_string(gap.first_frame) + "+" +
            std::to_string(gap.length) + " ";
  EXPECT_EQ(text, "0:539+5 1:1077+17 ");
}

TEST(GapPlan, RespectsLengthsMarginsFrameZeroAndChannels) {
  const Capture capture = full_capture(30, 6000);
  const GapPlanOptions options{.seed = 3, .min_frames = 3, .max_seconds = 4.0, .margin_frames = 2};
  const std::vector<Gap> plan = plan_gaps(capture, options);
  ASSERT_FALSE(plan.empty());
  for (size_t i = 0; i < plan.size(); ++i) {
    const Gap& gap = plan[i];
    EXPECT_TRUE(capture.is_labelled(gap.point));
    EXPECT_GE(gap.length, 3);
    EXPECT_LE(gap.length, 480);
    EXPECT_GE(gap.first_frame, 2);  // margin before, and frame 0 never covered
    EXPECT_LE(gap.first_frame + gap.length + 2, capture.frame_count);
    if (i > 0 && plan[i - 1].point == gap.point) {  // sorted, apart by at least the margin
      EXPECT_GE(gap.first_frame, plan[i - 1].first_frame + plan[i - 1].length + 2);
    }
    if (i > 0) {
      EXPECT_TRUE(plan[i - 1].point < gap.point || plan[i - 1].first_frame < gap.first_frame);
    }
  }
}

TEST(GapPlan, FrameZeroStaysPresentEvenWithoutMargin) {
  const Capture capture = full_capture(40, 600);
  for (const Gap& gap :
       plan_gaps(capture, {.seed = 5, .gaps_per_marker_per_minute = 60.0, .margin_frames = 0}))
    EXPECT_GE(gap.first_frame, 1);
}

TEST(GapPlan, CountAndLengthsFollowTheOptions) {
  const Capture capture = full_capture(40, 7200);  // 1 minute at 120 Hz
  const std::vector<Gap> plan = plan_gaps(capture, {.seed = 11});
  // 6 per marker per minute: 240 expected, a few may not fit.
  EXPECT_GE(plan.size(), 216u);
  EXPECT_LE(plan.size(), 264u);
  // Log-uniform from 3 to 480 frames: about half below the geometric mean (~38 frames),
  // both a few-frame and a several-second occlusion present.
  const auto below = std::count_if(plan.begin(), plan.end(), [](const Gap& g) { return g.length < 38; });
  EXPECT_NEAR(static_cast<double>(below) / plan.size(), 0.5, 0.12);
  EXPECT_TRUE(std::any_of(plan.begin(), plan.end(), [](const Gap& g) { return g.length <= 5; }));
  EXPECT_TRUE(std::any_of(plan.begin(), plan.end(), [](const Gap& g) { return g.length >= 360; }));
}

TEST(GapPlan, SeveralMarkersGoMissingTogether) {
  const Capture capture = full_capture(20, 4800);
  const Capture holed = apply_gaps(capture, plan_gaps(capture, {.seed = 2}));
  int most_missing = 0;
  for (int f = 0; f < holed.frame_count; ++f) {
    int missing = 0;
    for (int p = 0; p < holed.point_count(); ++p) missing += !holed.present(f, p);
    most_missing = std::max(most_missing, missing);
  }
  EXPECT_GE(most_missing, 3);
}

TEST(GapPlan, KeepsAwayFromSamplesAlreadyMissing) {
  Capture capture = full_capture(1, 2400);
  for (int f = 1000; f < 1400; ++f) capture.at(f, 0) = missing_point();
  for (uint64_t seed = 1; seed <= 20; ++seed)
    for (const Gap& gap :
         plan_gaps(capture, {.seed = seed, .gaps_per_marker_per_minute = 30.0, .margin_frames = 3})) {
      const bool before = gap.first_frame + gap.length + 3 <= 1000;
      const bool after = gap.first_frame - 3 >= 1400;
      EXPECT_TRUE(before || after) << gap.first_frame << "+" << gap.length;
    }
}

TEST(GapPlan, NoGapsWhenTheRateOfGapsIsZeroOrTheCaptureTooShort) {
  EXPECT_TRUE(plan_gaps(full_capture(5, 1000), {.gaps_per_marker_per_minute = 0.0}).empty());
  EXPECT_TRUE(plan_gaps(full_capture(5, 6), {.min_frames = 3, .gaps_per_marker_per_minute = 6000.0}).empty());
}

// The long-gap protocol: 2-6 s occlusions of three markers at once until 4 % of the samples
// are missing, each gap interior with its margins, never overlapping on a channel.
TEST(GapPlan, LongGapProtocolCoversItsShareWithGroupsOfThreeLongGaps) {
  const Capture capture = full_capture(40, 6000);  // 50 s at 120 Hz
  const GapPlanOptions options = long_gap_plan(4);
  const std::vector<Gap> plan = plan_gaps(capture, options);
  long samples = 0;
  std::map<std::pair<int, int>, int> markers_per_span;
  for (const Gap& g : plan) {
    EXPECT_GE(g.length, 240);
    EXPECT_LE(g.length, 720);
    EXPECT_GE(g.first_frame, options.margin_frames);
    EXPECT_LE(g.first_frame + g.length + options.margin_frames, capture.frame_count);
    samples += g.length;
    ++markers_per_span[{g.first_frame, g.length}];
  }
  const double share = static_cast<double>(samples) / (40.0 * 6000.0);
  EXPECT_GE(share, 0.04);
  EXPECT_LE(share, 0.04 + 3.0 * 720 / (40.0 * 6000.0));  // overshoots by one group at most
  for (const auto& [span, markers] : markers_per_span) EXPECT_EQ(markers % 3, 0) << span.first;
  for (size_t a = 0; a < plan.size(); ++a)
    for (size_t b = a + 1; b < plan.size(); ++b)
      if (plan[a].point == plan[b].point) {
        EXPECT_TRUE(plan[a].first_frame + plan[a].length + options.margin_frames <= plan[b].first_frame ||
                    plan[b].first_frame + plan[b].length + options.margin_frames <= plan[a].first_frame);
      }
}

TEST(GapPlan, ApplySetsExactlyThoseSamplesMissing) {
  const Capture capture = full_capture(3, 50);
  const Capture holed = apply_gaps(capture, {{0, 5, 3}, {2, 10, 1}, {0, 20, 2}});
  for (int f = 0; f < 50; ++f)
    for (int p = 0; p < capture.point_count(); ++p) {
      const bool knocked = (p == 0 && ((f >= 5 && f < 8) || (f >= 20 && f < 22))) || (p == 2 && f == 10);
      EXPECT_EQ(holed.present(f, p), !knocked) << f << " " << p;
      if (!knocked) {
        EXPECT_EQ(holed.at(f, p), capture.at(f, p));
      }
    }
}

}  // namespace
}  // namespace skinstream
