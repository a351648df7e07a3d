#pragma once
// What a subscriber received against the recording the source streamed: every marker finite,
// the measured samples unchanged (C3D float -> Vicon double / QTM float / NatNet float metres ->
// published float, NatNet's metres within 0.2 um), and, on a stage with another actor, no marker
// nearer that actor than its own.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <span>
#include <sstream>
#include <string>
#include <vector>

#include "core/capture.h"

namespace skinstream::test {

// The frame lines of skinstream-sub --json output (the summary line left out).
inline std::vector<nlohmann::json> frames_of(const std::string& sub_output) {
  std::vector<nlohmann::json> frames;
  std::istringstream lines(sub_output);
  for (std::string line; std::getline(lines, line);) {
    const nlohmann::json j = nlohmann::json::parse(line);
    if (j.contains("frame")) frames.push_back(j);
  }
  return frames;
}

class RecordingMatch {
 public:
  // other_actor_x: where the stage's other actor stands relative to this one, along x (0: alone).
  explicit RecordingMatch(const Capture& own, double other_actor_x = 0.0) : own_(own), other_x_(other_actor_x) {}

  // One frame's filled markers (3M floats, the subject's order = the recording's channels).
  void add(uint32_t frame_number, std::span<const float> live) {
    ASSERT_GE(static_cast<int>(frame_number), own_.first_frame);
    const int index = (static_cast<int>(frame_number) - own_.first_frame) % own_.frame_count;
    const int markers = own_.point_count();
    ASSERT_EQ(live.size(), static_cast<size_t>(3 * markers));
    Vec3 centre = Vec3::Zero();
    int present = 0;
    for (int m = 0; m < markers; ++m) {
      for (int a = 0; a < 3; ++a) ASSERT_TRUE(std::isfinite(live[3 * m + a])) << "frame " << frame_number << " marker " << m;
      const Vec3 sample = own_.at(index, m);
      if (!is_present(sample)) continue;
      ++measured_;
      centre += sample;
      ++present;
      if ((Vec3(live[3 * m], live[3 * m + 1], live[3 * m + 2]) - sample).norm() < 1e-3) ++equal_;
    }
    if (other_x_ == 0.0 || present == 0) return;
    centre /= present;
    const Vec3 other = centre + Vec3(other_x_, 0.0, 0.0);
    for (int m = 0; m < markers; ++m) {
      const Vec3 p(live[3 * m], live[3 * m + 1], live[3 * m + 2]);
      ASSERT_LT((p - centre).norm(), (p - other).norm()) << "frame " << frame_number << " marker " << m << " is nearer the other actor";
    }
  }
  void add(const nlohmann::json& sub_frame) {
    const std::vector<float> live = sub_frame["markers"];
    add(sub_frame["frame"].get<uint32_t>(), live);
  }

  // The relabeller may refuse a label now and then; the mapping is wrong if many differ.
  void expect_measured_samples_unchanged() const {
    ASSERT_GT(measured_, 0);
    EXPECT_GE(equal_, measured_ * 99 / 100) << equal_ << " of " << measured_ << " measured samples equal the recording";
  }

 private:
  const Capture& own_;
  double other_x_;
  long measured_ = 0, equal_ = 0;
};

// Frame numbers rise (the replay numbers frames across loops) and the frames follow `recording`.
inline void expect_frames_follow_recording(const Capture& recording, const std::vector<nlohmann::json>& frames,
                                           double other_actor_x = 0.0) {
  RecordingMatch match(recording, other_actor_x);
  for (size_t i = 0; i < frames.size(); ++i) {
    if (i > 0) {
      EXPECT_GT(frames[i]["frame"].get<int>(), frames[i - 1]["frame"].get<int>()) << "frame " << i;
    }
    match.add(frames[i]);
  }
  match.expect_measured_samples_unchanged();
}

}  // namespace skinstream::test
