#pragma once
// Runs skinstream's own relabeller and gap filler (online, lookahead 0 unless told) over a synthetic capture
// and judges them against its truth: Park & Hodgins' Table 1 after merging and Table 2.
#include <nlohmann/json.hpp>

#include "core/synth/synth_capture.h"

namespace skinstream::cli {

// `training` is a range-of-motion take of the same body and marker layout (same seed).
// `lookahead`: frames, as `skinstream fill --lookahead` (the relabels confirmed over them).
nlohmann::ordered_json evaluate_on_synthetic(const synth::SynthCapture& take, const synth::SynthCapture& training,
                                             int lookahead = 0);

}  // namespace skinstream::cli
