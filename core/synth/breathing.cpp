#include "core/synth/breathing.h"

namespace skinstream::synth {

std::vector<BreathingPart> standard_breathing(const Body& body, const Anatomy& a) {
  const Skeleton& sk = body.skeleton;
  std::vector<int> chest_bones, belly_bones;
  for (int b : {a.spine[3], a.spine[4], sk.find("breast.L"), sk.find("breast.R"), a.arm[kLeft].clavicle,
                a.arm[kRight].clavicle})
    if (b >= 0) chest_bones.push_back(b);
  for (int b : {a.spine[0], a.spine[1], a.spine[2]})
    if (b >= 0) belly_bones.push_back(b);

  const Vec3 chest_centre =
      sk.bone(a.spine[3]).head + 0.5 * (sk.bone(a.spine[3]).tail - sk.bone(a.spine[3]).head);
  const Vec3 belly_centre =
      sk.bone(a.spine[1]).head + 0.5 * (sk.bone(a.spine[2]).tail - sk.bone(a.spine[1]).head);

  std::vector<BreathingPart> out;
  BreathingPart chest;
  chest.name = "chest";
  chest.region.centre = chest_centre;
  chest.region.axis = kAxisUp;
  chest.region.sigma_along = 130.0;
  chest.region.facing = kAxisForward;
  chest.region.facing_power = 1.0;
  chest.region.mask_bones = chest_bones;
  chest.amplitude_mm = 9.0;
  out.push_back(chest);

  for (Side s : {kLeft, kRight}) {
    BreathingPart ribs = chest;
    ribs.name = std::string("ribs_") + side_suffix(s);
    ribs.region.centre = chest_centre - 60.0 * kAxisUp;
    ribs.region.facing = lateral_sign(s) * kAxisRight;
    ribs.region.facing_power = 1.5;
    ribs.amplitude_mm = 4.0;
    out.push_back(ribs);
  }

  BreathingPart belly;
  belly.name = "belly";
  belly.region.centre = belly_centre;
  belly.region.axis = kAxisUp;
  belly.region.sigma_along = 110.0;
  belly.region.facing = kAxisForward;
  belly.region.facing_power = 1.5;
  belly.region.mask_bones = belly_bones;
  belly.amplitude_mm = 18.0;
  out.push_back(belly);
  return out;
}

}  // namespace skinstream::synth
