#include "core/synth/trajectory_breaker.h"

#include <gtest/gtest.h>

#include <cmath>

namespace skinstream::synth {
namespace {

// n markers on a line 40 mm apart moving slowly; visibility all on unless told otherwise.
Capture line(int n, int frames) {
  std::vector<std::string> names;
  for (int i = 0; i < n; ++i) names.push_back("m_" + std::to_string(i + 1));
  Capture c(names, frames, 120.0);
  for (int f = 0; f < frames; ++f)
    for (int i = 0; i < n; ++i) c.at(f, i) = Vec3(40.0 * i, 0.2 * f, 1000.0 + 10.0 * std::sin(f / 30.0));
  return c;
}

std::vector<std::vector<int>> chain_neighbours(int n) {
  std::vector<std::vector<int>> nb(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) {
    if (i > 0) nb[static_cast<size_t>(i)].push_back(i - 1);
    if (i + 1 < n) nb[static_cast<size_t>(i)].push_back(i + 1);
  }
  return nb;
}

BreakOptions quiet() {  // no random breaks, ghosts or wrong labels
  BreakOptions o;
  o.random_breaks_per_s = 0.0;
  o.break_max_probability = 0.0;
  o.ghosts_per_s = 0.0;
  o.wrong_label = 0.0;
  o.wrong_label_close = 0.0;
  return o;
}

TEST(SynthBreaker, RejectsInconsistentInputs) {
  const Capture t = line(3, 10);
  Random r(1);
  const std::vector<uint8_t> vis(30, 1);
  EXPECT_THROW(break_trajectories(t, std::vector<uint8_t>(29, 1), chain_neighbours(3), quiet(), r),
               std::invalid_argument);
  EXPECT_THROW(break_trajectories(t, vis, chain_neighbours(2), quiet(), r), std::invalid_argument);
  Capture holed = t;
  holed.at(4, 1) = missing_point();
  EXPECT_THROW(break_trajectories(holed, vis, chain_neighbours(3), quiet(), r), std::invalid_argument);
  Capture unlabelled = t;
  unlabelled.labels[2] = "*0";
  EXPECT_THROW(break_trajectories(unlabelled, vis, chain_neighbours(3), quiet(), r), std::invalid_argument);
}

TEST(SynthBreaker, AlwaysVisibleMarkersGiveOneLabelledTrajectoryEach) {
  const Capture t = line(5, 200);
  Random r(2);
  BreakOptions o = quiet();
  o.noise_mm = 0.3;
  const BrokenCapture b = break_trajectories(t, std::vector<uint8_t>(1000, 1), chain_neighbours(5), o, r);
  EXPECT_EQ(b.capture.point_count(), 5);
  EXPECT_EQ(b.counts.trajectories, 5);
  EXPECT_EQ(b.counts.holes, 0);
  EXPECT_EQ(b.counts.missing_fraction, 0.0);
  double sum2 = 0.0;
  for (int f = 0; f < 200; ++f)
    for (int i = 0; i < 5; ++i) sum2 += (b.capture.at(f, i) - t.at(f, i)).squaredNorm();
  const double rms = std::sqrt(sum2 / (3.0 * 1000));
  EXPECT_NEAR(rms, 0.3, 0.03);  // sub-millimetre noise per coordinate
}

TEST(SynthBreaker, GapsEndTrajectoriesAndReturningMarkersMayComeBackUnlabelled) {
  const int n = 40, frames = 300;
  const Capture t = line(n, frames);
  std::vector<uint8_t> vis(static_cast<size_t>(n * frames), 1);
  for (int i = 0; i < n; ++i)
    for (int f = 100; f < 100 + 3 + (i % 20); ++f) vis[static_cast<size_t>(f * n + i)] = 0;  // one gap each
  BreakOptions o = quiet();
  o.relabel_after_short_gap = 0.5;
  o.relabel_after_long_gap = 0.5;
  Random r(3);
  const BrokenCapture b = break_trajectories(t, vis, chain_neighbours(n), o, r);
  EXPECT_EQ(b.counts.trajectories, 2 * n);  // every gap ends a trajectory
  EXPECT_GT(b.counts.unlabelled_fragments, 8);
  EXPECT_LT(b.counts.unlabelled_fragments, 32);
  EXPECT_EQ(b.capture.point_count(), n + b.counts.unlabelled_fragments);
  for (int ch = n; ch < b.capture.point_count(); ++ch)
    EXPECT_TRUE(is_unlabelled_name(b.capture.labels[static_cast<size_t>(ch)]));
  EXPECT_EQ(b.counts.gaps, n);
  long hidden = 0;
  for (uint8_t v : vis) hidden += v == 0;
  EXPECT_EQ(b.counts.holes, hidden);
  // Every delivered sample is its source marker's truth plus noise; missing ones are NaN.
  for (int f = 0; f < frames; ++f)
    for (int ch = 0; ch < b.capture.point_count(); ++ch) {
      const int s = b.source_at(f, ch);
      if (s >= 0)
        ASSERT_LT((b.capture.at(f, ch) - t.at(f, s)).norm(), 3.0);
      else
        ASSERT_FALSE(b.capture.present(f, ch));
    }
}

TEST(SynthBreaker, WrongLabelsSwapWithANeighbourAndGhostsAppear) {
  const int n = 30, frames = 240;
  const Capture t = line(n, frames);
  std::vector<uint8_t> vis(static_cast<size_t>(n * frames), 1);
  for (int i = 0; i < n; i += 2)
    for (int f = 60; f < 70; ++f) vis[static_cast<size_t>(f * n + i)] = 0;
  BreakOptions o = quiet();
  o.wrong_label = 1.0;  // every returning fragment is mislabelled
  o.ghosts_per_s = 5.0;
  Random r(4);
  const BrokenCapture b = break_trajectories(t, vis, chain_neighbours(n), o, r);
  EXPECT_GE(b.counts.wrong_label_fragments, n / 2);
  EXPECT_GT(b.counts.ghost_trajectories, 2);
  int runs = 0;  // fragments share unlabelled channels, never touching: each is a run
  for (int ch = n; ch < b.capture.point_count(); ++ch)
    for (int f = 0; f < b.capture.frame_count; ++f) runs += b.capture.present(f, ch) && (f == 0 || !b.capture.present(f - 1, ch));
  EXPECT_EQ(b.counts.ghost_trajectories + b.counts.unlabelled_fragments, runs);
  EXPECT_LE(b.capture.point_count() - n, runs);
  // A mislabelled sample belongs to a neighbour of the channel's marker.
  for (int f = 0; f < frames; ++f)
    for (int ch = 0; ch < n; ++ch) {
      const int s = b.source_at(f, ch);
      if (s >= 0 && s != ch) {
        ASSERT_EQ(std::abs(s - ch), 1);
      }
    }
}

TEST(SynthBreaker, FastMarkersBreakMoreAndTheSameSeedBreaksTheSame) {
  const int n = 20, frames = 240;
  Capture slow = line(n, frames), fast = line(n, frames);
  for (int f = 0; f < frames; ++f)
    for (int i = 0; i < n; ++i)
      fast.at(f, i) += Vec3(0, 0, 40.0 * std::sin(f * 0.3));  // 5 g at 5.7 Hz, like a fist
  BreakOptions o;
  o.ghosts_per_s = 0.0;
  const std::vector<uint8_t> vis(static_cast<size_t>(n * frames), 1);
  Random r1(9), r2(9), r3(9);
  const BrokenCapture a = break_trajectories(slow, vis, chain_neighbours(n), o, r1);
  const BrokenCapture b = break_trajectories(fast, vis, chain_neighbours(n), o, r2);
  const BrokenCapture c = break_trajectories(fast, vis, chain_neighbours(n), o, r3);
  EXPECT_GT(b.counts.trajectories, a.counts.trajectories + 3 * n);
  EXPECT_EQ(b.source, c.source);
  EXPECT_EQ(b.capture.labels, c.capture.labels);
  for (size_t k = 0; k < b.capture.positions.size(); ++k)
    ASSERT_TRUE(b.capture.positions[k] == c.capture.positions[k] ||
                (!is_present(b.capture.positions[k]) && !is_present(c.capture.positions[k])));
}

}  // namespace
}  // namespace skinstream::synth
