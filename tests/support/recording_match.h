#pragma once
// What a subscriber received (skinstream-sub --markers --json lines) against the recording the
// source streamed: frames in order, every marker finite, and the measured samples unchanged.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
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

// Frame numbers rise (the replay numbers frames across loops), every marker is finite, and 99%
// of the recording's measured samples arrive unchanged (C3D float -> Vicon double -> published
// float; the relabeller may refuse a label now and then, the mapping is wrong if many differ).
inline void expect_frames_follow_recording(const Capture& recording, const std::vector<nlohmann::json>& frames) {
  const int markers = recording.point_count();
  long measured = 0, measured_equal = 0;
  for (size_t i = 0; i < frames.size(); ++i) {
    const int number = frames[i]["frame"];
    if (i > 0) {
      EXPECT_GT(number, frames[i - 1]["frame"].get<int>()) << "frame " << i;
    }
    ASSERT_GE(number, recording.first_frame);
    const int index = (number - recording.first_frame) % recording.frame_count;
    const std::vector<float> live = frames[i]["markers"];
    ASSERT_EQ(live.size(), static_cast<size_t>(3 * markers));
    for (int m = 0; m < markers; ++m) {
      for (int a = 0; a < 3; ++a) ASSERT_TRUE(std::isfinite(live[3 * m + a])) << "frame " << number << " marker " << m;
      const Vec3 sample = recording.at(index, m);
      if (!is_present(sample)) continue;
      ++measured;
      const Vec3 got(live[3 * m], live[3 * m + 1], live[3 * m + 2]);
      if ((got - sample).norm() < 1e-3) ++measured_equal;
    }
  }
  ASSERT_GT(measured, 0);
  EXPECT_GE(measured_equal, measured * 99 / 100) << measured_equal << " of " << measured << " measured samples equal the recording";
}

}  // namespace skinstream::test
