#include "core/fitting/take_motion.h"

#include <algorithm>
#include <cstdio>
#include <limits>
#include <vector>

namespace skinstream {

TakeMotion measure_take_motion(std::span<const Vec3> frames, int frame_count, int markers, const TakeMotionLimits& limits) {
  TakeMotion out;
  const int sampled = std::max(1, std::min(frame_count, limits.max_frames));
  const size_t pair_count = static_cast<size_t>(markers) * (markers - 1) / 2;
  std::vector<double> shortest(pair_count, std::numeric_limits<double>::infinity());
  std::vector<double> longest(pair_count, -std::numeric_limits<double>::infinity());
  for (int k = 0; k < sampled; ++k) {
    const int f = static_cast<int>((static_cast<long long>(k) * frame_count) / sampled);
    const Vec3* frame = frames.data() + static_cast<size_t>(f) * markers;
    size_t pair = 0;
    for (int a = 0; a < markers; ++a)
      for (int b = a + 1; b < markers; ++b, ++pair) {
        if (!is_present(frame[a]) || !is_present(frame[b])) continue;
        const double d = (frame[a] - frame[b]).norm();
        shortest[pair] = std::min(shortest[pair], d);
        longest[pair] = std::max(longest[pair], d);
      }
  }
  std::vector<double> ranges;
  for (size_t p = 0; p < pair_count; ++p)
    if (longest[p] >= shortest[p]) ranges.push_back(longest[p] - shortest[p]);
  out.pairs = static_cast<int>(ranges.size());
  if (!ranges.empty()) {
    const size_t at = std::min(ranges.size() - 1, static_cast<size_t>(0.75 * static_cast<double>(ranges.size())));
    std::nth_element(ranges.begin(), ranges.begin() + static_cast<std::ptrdiff_t>(at), ranges.end());
    out.articulation_mm = ranges[at];
  }
  if (out.articulation_mm < limits.min_articulation_mm) {
    char line[320];
    std::snprintf(line, sizeof line,
                  "the markers barely change their distances to each other over the take (%.0f mm, a body's range of "
                  "motion moves them %.0f mm or more): a rigid object or an actor standing still, nothing to fit joints to",
                  out.articulation_mm, limits.min_articulation_mm);
    out.problem = line;
  }
  return out;
}

}  // namespace skinstream
