#pragma once
// Gaps made on purpose in a test capture.
#include "core/capture.h"

namespace skinstream::test {

// Frames [first, first + length) of `point` become missing.
inline void knock_out(Capture& capture, int point, int first, int length) {
  for (int f = first; f < first + length; ++f) capture.at(f, point) = missing_point();
}

}  // namespace skinstream::test
