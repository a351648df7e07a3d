#include "core/evaluation/merge_stats.h"

#include <gtest/gtest.h>

namespace skinstream {
namespace {

TEST(MergeStats, RejectsMismatchedSizes) {
  Capture c({"a", "*0"}, 3, 120.0);
  EXPECT_THROW(merge_stats(c, {}, {0}, {}, {}), std::invalid_argument);
}

// Marker a is channel 0 for frames 0-1, then comes back on "*0" (frames 3-4); "*1" is a ghost
// (frame 4) and "*2" is marker a's neighbour b mislabelled onto nothing (frame 2).
TEST(MergeStats, CountsMergedUnmergedAndWrongFragments) {
  Capture c({"a", "b", "*0", "*1"}, 5, 120.0);
  std::vector<int> truth(5 * 4, -2);
  auto put = [&](int f, int ch, int who) {
    c.at(f, ch) = Vec3(f, ch, 0);
    truth[f * 4 + ch] = who;
  };
  for (int f = 0; f < 5; ++f) put(f, 1, 1);  // b, always there
  put(0, 0, 0);
  put(1, 0, 0);
  put(3, 2, 0);
  put(4, 2, 0);
  put(4, 3, -1);  // ghost
  const std::vector<int> channel_of = {0, 1};
  std::vector<MarkerStatus> status(5 * 2, MarkerStatus::Measured);
  std::vector<int> fragments(5 * 2, -1);
  status[2 * 2 + 0] = MarkerStatus::FilledPca;
  status[3 * 2 + 0] = status[4 * 2 + 0] = MarkerStatus::Relabelled;
  fragments[3 * 2 + 0] = 2;
  fragments[4 * 2 + 0] = 2;
  MergeStats s = merge_stats(c, truth, channel_of, status, fragments);
  EXPECT_EQ(s.fragments, 4);  // a's first part, b, *0, *1
  EXPECT_EQ(s.unmerged_fragments, 1);  // the ghost
  EXPECT_EQ(s.trajectories_after, 3);  // a, b, the ghost
  EXPECT_EQ(s.wrong_fragments, 0);

  // Now the ghost is taken for a in frame 4 instead of *0: one wrong fragment, *0 partly unused.
  fragments[4 * 2 + 0] = 3;
  s = merge_stats(c, truth, channel_of, status, fragments);
  EXPECT_EQ(s.wrong_fragments, 1);
  EXPECT_EQ(s.wrong_samples, 1);
  EXPECT_EQ(s.wrong_relabelled_fragments, 1);
  EXPECT_EQ(s.wrong_measured_fragments, 0);
  EXPECT_EQ(s.unmerged_fragments, 0);
  ASSERT_EQ(s.wrong_list.size(), 1u);
  EXPECT_EQ(s.wrong_list[0].channel, 3);
  EXPECT_EQ(s.wrong_list[0].first_wrong_frame, 4);
  EXPECT_EQ(s.wrong_list[0].true_marker, -1);
  EXPECT_EQ(s.wrong_list[0].taken_by, 0);
  EXPECT_TRUE(s.wrong_list[0].relabelled);

  // And b's channel delivers a's point in frame 2 (a mislabel), kept as b's measurement.
  truth[2 * 4 + 1] = 0;
  s = merge_stats(c, truth, channel_of, status, fragments);
  EXPECT_EQ(s.wrong_fragments, 2);
  EXPECT_EQ(s.wrong_measured_fragments, 1);
  EXPECT_EQ(s.wrong_relabelled_fragments, 1);
  ASSERT_EQ(s.wrong_list.size(), 2u);  // by channel: b's first
  const WrongFragment& b = s.wrong_list[0];
  EXPECT_EQ(b.channel, 1);
  EXPECT_EQ(b.first_frame, 0);
  EXPECT_EQ(b.last_frame, 4);
  EXPECT_EQ(b.first_wrong_frame, 2);
  EXPECT_EQ(b.wrong_samples, 1);
  EXPECT_EQ(b.true_marker, 0);
  EXPECT_EQ(b.taken_by, 1);
  EXPECT_FALSE(b.relabelled);
}

// a's own channel delivers a's point in frames 0-2; the filler kept frame 0, rejected frame 1 and
// gave it back as a relabel (the rejected point of marker a is its own channel), and rejected
// frame 2 for good (filled): one true label not kept. b's mislabelled sample in frame 2 is not a
// true label, so b filled there does not count.
TEST(MergeStats, CountsTrueLabelsNotKept) {
  Capture c({"a", "b"}, 3, 120.0);
  std::vector<int> truth(3 * 2, -2);
  for (int f = 0; f < 3; ++f) {
    c.at(f, 0) = Vec3(f, 0, 0);
    truth[f * 2 + 0] = 0;
    c.at(f, 1) = Vec3(f, 1, 0);
    truth[f * 2 + 1] = f == 2 ? 0 : 1;
  }
  std::vector<MarkerStatus> status(3 * 2, MarkerStatus::Measured);
  std::vector<int> fragments(3 * 2, -1);
  status[1 * 2 + 0] = MarkerStatus::Relabelled;
  fragments[1 * 2 + 0] = 0;
  status[2 * 2 + 0] = MarkerStatus::FilledPca;
  status[2 * 2 + 1] = MarkerStatus::FilledPca;
  const MergeStats s = merge_stats(c, truth, {0, 1}, status, fragments);
  EXPECT_EQ(s.true_labels_not_kept, 1);
}

}  // namespace
}  // namespace skinstream
