#include "core/baselines/linear_interpolation_fill.h"

#include "core/baselines/channel_runs.h"

namespace skinstream {

Capture fill_linear(const Capture& capture) {
  require_consistent(capture, "fill_linear");
  Capture filled = capture;
  for (int point : capture.labelled_points()) {
    const std::vector<int> present = present_frames(capture, point);
    hold_ends(filled, point, present);
    for (size_t k = 0; k + 1 < present.size(); ++k) {
      const int before = present[k], after = present[k + 1];
      if (after - before < 2) continue;
      const Vec3 from = capture.at(before, point), to = capture.at(after, point);
      for (int f = before + 1; f < after; ++f) {
        const double t = static_cast<double>(f - before) / (after - before);
        filled.at(f, point) = from + t * (to - from);
      }
    }
  }
  return filled;
}

}  // namespace skinstream
