#include "core/capture_filler.h"

#include <gtest/gtest.h>

#include "core/offline/subject_builder.h"
#include "support/synthetic_limb.h"

namespace skinstream {
namespace {

TEST(CaptureFiller, ReportsUnknownLabelsAndAbsentMarkers) {
  const Capture limb = test::make_limb_capture();
  const SubjectModel model = build_subject(limb, {});
  Capture other = limb;
  other.labels[0] = "stranger";
  CaptureFillReport report;
  const std::vector<int> channel_of = map_channels_to_markers(model, other, &report);
  EXPECT_EQ(channel_of[0], -1);
  EXPECT_EQ(channel_of[1], 1);
  EXPECT_EQ(report.unknown_labels, std::vector<std::string>{"stranger"});
  EXPECT_EQ(report.absent_markers, std::vector<std::string>{limb.labels[0]});
}

TEST(CaptureFiller, MergesABrokenTrajectoryAndSaysWhichChannelItCameFrom) {
  const Capture limb = test::make_limb_capture();
  const SubjectModel model = build_subject(limb, {});
  // Marker 26 breaks at frame 100: the rest of its trajectory arrives as unlabelled channel "*0".
  std::vector<std::string> labels = limb.labels;
  labels.push_back("*0");
  Capture broken(labels, limb.frame_count, limb.rate_hz);
  const int marker = 26, extra = limb.point_count();
  for (int f = 0; f < limb.frame_count; ++f) {
    for (int p = 0; p < limb.point_count(); ++p) broken.at(f, p) = limb.at(f, p);
    if (f >= 100) {
      broken.at(f, extra) = broken.at(f, marker);
      broken.at(f, marker) = missing_point();
    }
  }
  std::vector<MarkerStatus> status;
  std::vector<int> fragments;
  CaptureFillReport report;
  const Capture filled = fill_capture(model, broken, {}, &status, &report, &fragments);
  const int n = model.marker_count();
  for (int f = 100; f < limb.frame_count; ++f) {
    EXPECT_EQ(status[static_cast<size_t>(f) * n + marker], MarkerStatus::Relabelled) << f;
    EXPECT_EQ(fragments[static_cast<size_t>(f) * n + marker], extra);
    EXPECT_EQ(filled.at(f, marker), limb.at(f, marker));
  }
  EXPECT_EQ(fragments[static_cast<size_t>(99) * n + marker], -1);
  EXPECT_EQ(report.relabelled, limb.frame_count - 100);
  EXPECT_EQ(report.filled, 0);
}

}  // namespace
}  // namespace skinstream
