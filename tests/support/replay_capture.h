#pragma once
// A small recording for the replay servers and the sources that read them: labelled markers A and
// B (B occluded every third frame) and an unlabelled point "*3", at 120 Hz from frame 100, with
// non-round coordinates shifted by `offset` mm (so two subjects differ).
#include <cmath>

#include "core/capture.h"

namespace skinstream::test {

inline Capture replay_capture(int frames, double offset) {
  Capture c({"A", "B", "*3"}, frames, 120.0);
  c.first_frame = 100;
  for (int f = 0; f < frames; ++f)
    for (int p = 0; p < c.point_count(); ++p)
      c.at(f, p) = Vec3(std::sin(0.1 * f + p) * 1000.0 / 3.0 + offset, p * 17.25 + f / 7.0, std::cos(0.05 * f) * 1e3);
  for (int f = 0; f < frames; f += 3) c.at(f, 1) = missing_point();
  return c;
}

}  // namespace skinstream::test
