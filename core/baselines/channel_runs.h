#pragma once
// Shared by the interpolating fillers: where one channel's samples are present.

#include <stdexcept>
#include <vector>

#include "core/capture.h"

namespace skinstream {

// Frame indices at which `point` is present, ascending.
inline std::vector<int> present_frames(const Capture& capture, int point) {
  std::vector<int> frames;
  for (int f = 0; f < capture.frame_count; ++f)
    if (capture.present(f, point)) frames.push_back(f);
  return frames;
}

// A filler's precondition: the positions array really is labels x frames.
inline void require_consistent(const Capture& capture, const char* who) {
  if (capture.frame_count < 0 ||
      capture.positions.size() != static_cast<size_t>(capture.frame_count) * capture.labels.size())
    throw std::invalid_argument(std::string(who) + ": positions do not match labels x frame_count");
}

// Fills the frames before the first and after the last present sample with those samples.
inline void hold_ends(Capture& capture, int point, const std::vector<int>& present) {
  if (present.empty()) return;
  const Vec3 first = capture.at(present.front(), point);
  const Vec3 last = capture.at(present.back(), point);
  for (int f = 0; f < present.front(); ++f) capture.at(f, point) = first;
  for (int f = present.back() + 1; f < capture.frame_count; ++f) capture.at(f, point) = last;
}

}  // namespace skinstream
