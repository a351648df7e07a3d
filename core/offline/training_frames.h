#pragma once
// The frames of a training take that the offline choices sample: up to `sample_frames` spread
// evenly over the take.

#include <algorithm>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/capture.h"

namespace skinstream {

// Throws std::invalid_argument, naming `who`, unless `training` is frame_count x marker_count
// with at least one frame. The choices call it first, before any early return.
inline void check_training_take(const std::string& who, std::span<const Vec3> training, int frame_count,
                                int marker_count) {
  if (frame_count <= 0 || training.size() != static_cast<size_t>(frame_count) * marker_count)
    throw std::invalid_argument(who + ": training is not frame_count x marker_count");
}

// Calls visit(frame, members) for each sampled frame of `training` (checked by
// check_training_take), with `members` the positions of `member_markers` in that frame, and
// returns how many frames it visited.
template <typename Visit>
int for_each_training_frame(std::span<const int> member_markers, std::span<const Vec3> training, int frame_count,
                            int marker_count, int sample_frames, Visit&& visit) {
  std::vector<Vec3> members(member_markers.size());
  const int frames = std::min(std::max(sample_frames, 1), frame_count);
  for (int s = 0; s < frames; ++s) {
    const int frame = static_cast<int>((static_cast<long long>(s) * frame_count) / frames);
    for (size_t i = 0; i < members.size(); ++i)
      members[i] = training[static_cast<size_t>(frame) * marker_count + member_markers[i]];
    visit(frame, static_cast<const std::vector<Vec3>&>(members));
  }
  return frames;
}

}  // namespace skinstream
