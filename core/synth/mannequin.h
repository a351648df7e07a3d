#pragma once
// A procedural stand-in for the MakeHuman body: closed capsules for trunk, head, neck and limbs
// around a skeleton with MakeHuman's bone names and (rounded) joint positions, skin weights by
// distance to the bones. About 1.7 m tall, A-pose, millimetres, Z up, facing +Y, soles at z = 0.
// For tests and benchmarks of the generator without the MakeHuman files.
#include "core/body/body.h"

namespace skinstream::synth {

// detail scales the tessellation (1: about 4,000 vertices). Throws std::invalid_argument for
// detail < 1.
Body make_mannequin(int detail = 1);

}  // namespace skinstream::synth
