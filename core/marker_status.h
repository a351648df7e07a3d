#pragma once
// What the gap filler did with each marker in a frame.
#include <cstdint>

namespace skinstream {

enum class MarkerStatus : uint8_t {
  Measured = 0,    // the capture system's labelled point, accepted
  Relabelled = 1,  // an unlabelled (or mislabelled) point matched to this marker (section 4.2)
  FilledPca = 2,   // estimated from the neighbours' PCA models (section 4.3)
  FilledRigid = 3, // estimated from the rigid fit of its neighbours (eq. 2)
  Held = 4,        // nothing usable nearby: held where it last was relative to its anchors
};

inline bool is_observed(MarkerStatus s) { return s == MarkerStatus::Measured || s == MarkerStatus::Relabelled; }
const char* to_string(MarkerStatus s);

}  // namespace skinstream
