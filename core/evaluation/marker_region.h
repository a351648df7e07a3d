#pragma once
// Body region of a marker from its name, to break fill errors down the way Park & Hodgins'
// Table 2 does (abdomen, elbow, thigh, knee, ...).

#include <string>
#include <vector>

namespace skinstream {

// The regions in head-to-toe order, "other" last:
//   head, torso (torso/abdomen, neck and back), shoulder, upper_arm, elbow, forearm,
//   hand (wrist/hand), pelvis, thigh, knee, shank, foot (ankle/foot), other.
const std::vector<std::string>& marker_regions();

// Maps a marker label to one of marker_regions(). Understands:
//   - Vicon Plug-in Gait and the CMU / HDM05 marker sets, with or without a "Subject:" prefix,
//     case-insensitive, side letter L/R first: LFHD RBHD (head); C7 T10 CLAV STRN RBAC RBAK
//     (torso); LSHO (shoulder); LUPA (upper_arm); LELB (elbow); LFRM (forearm); LWRA LWRB LWRI
//     LFIN LHND (hand); LFWT LBWT LASI LPSI SACR (pelvis); LTHI (thigh); LKNE (knee); LSHN LTIB
//     (shank); LANK LHEE LTOE LMT1 LMT5 (foot);
//   - grid names "<region>_<n>" (or "<region>_<n>_<m>") of the synthetic generator, e.g.
//     "abdomen_12", "elbow_3", "upper_arm_7", "thigh_2_5", optionally side-prefixed ("l_elbow_3",
//     "left_thigh_2"), and bare region words; with synonyms chest, back, neck, abdomen, belly
//     -> torso; wrist -> hand; hip -> pelvis; shin, calf -> shank; ankle, heel, toe -> foot;
//   - anything else, including unlabelled "*N" channels -> "other".
std::string marker_region(const std::string& label);

}  // namespace skinstream
