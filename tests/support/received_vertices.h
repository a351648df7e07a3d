#pragma once
// Vertices a subscriber received, by frame number, and their largest difference from another
// subscriber's of the same frames (the daemon's float buffer, usually).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <vector>

#include "skinstream/client.h"

namespace skinstream::test {

struct Received {
  std::vector<float> positions, normals;
};

struct Difference {
  double position_mm = 0.0;     // largest coordinate difference
  double normal_degrees = 0.0;  // largest angle between normals
  int frames = 0;               // frames both received
};

// What receive_frames() (support/client_frames.h) keeps of each frame for compare().
inline void keep_vertices(const client::Frame& frame, Received& r) {
  r.positions.assign(frame.positions.begin(), frame.positions.end());
  r.normals.assign(frame.normals.begin(), frame.normals.end());
}

inline Difference compare(const std::map<uint32_t, Received>& reference, const std::map<uint32_t, Received>& other) {
  Difference d;
  for (const auto& [number, frame] : other) {
    const auto it = reference.find(number);
    if (it == reference.end()) continue;
    ++d.frames;
    const Received& truth = it->second;
    EXPECT_EQ(frame.positions.size(), truth.positions.size());
    for (size_t i = 0; i < std::min(frame.positions.size(), truth.positions.size()); ++i)
      d.position_mm = std::max(d.position_mm, std::abs(double(frame.positions[i]) - truth.positions[i]));
    for (size_t v = 0; 3 * v + 2 < std::min(frame.normals.size(), truth.normals.size()); ++v) {
      // The angle as atan2(|a x b|, a . b): exact near 0, where acos of the dot product is not.
      const double a[3] = {frame.normals[3 * v], frame.normals[3 * v + 1], frame.normals[3 * v + 2]};
      const double b[3] = {truth.normals[3 * v], truth.normals[3 * v + 1], truth.normals[3 * v + 2]};
      const double cross[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
      const double sine = std::sqrt(cross[0] * cross[0] + cross[1] * cross[1] + cross[2] * cross[2]);
      const double cosine = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
      d.normal_degrees = std::max(d.normal_degrees, std::atan2(sine, cosine) * 180.0 / M_PI);
    }
  }
  return d;
}

}  // namespace skinstream::test
