#pragma once
// Reference gap filler: straight lines between the samples that bracket each gap.
// The weakest sensible baseline; every other filler should beat it on long gaps.

#include "core/capture.h"

namespace skinstream {

// Returns a copy of `capture` in which every labelled channel's missing samples are filled:
//   - a gap with present samples on both sides: linear interpolation in frame index between
//     the last present sample before it and the first present sample after it;
//   - a gap at the start or end of the capture: holds the nearest present sample;
//   - a channel with no present sample at all: stays missing.
// Unlabelled channels are returned unchanged. Throws std::invalid_argument when the
// positions array does not match labels x frame_count.
Capture fill_linear(const Capture& capture);

}  // namespace skinstream
