#pragma once
// Breathing of the torso: on inhalation the rib cage expands forward and sideways and the belly
// moves out (diaphragmatic breathing). Each part is a region whose skin moves along its normal
// by amplitude * breath, breath in 0..1 (0 = exhaled, 1 = deep inhalation).
#include <string>
#include <vector>

#include "core/body/anatomy.h"
#include "core/synth/body_region.h"

namespace skinstream::synth {

struct BreathingPart {
  std::string name;  // "chest", "ribs_L", "ribs_R", "belly"
  Region region;
  double amplitude_mm = 0.0;  // at breath = 1
};

std::vector<BreathingPart> standard_breathing(const Body& body, const Anatomy& anatomy);

inline double breathing_mm(const BreathingPart& part, double breath) { return part.amplitude_mm * breath; }

}  // namespace skinstream::synth
