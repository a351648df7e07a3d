#pragma once
// How QTM names the markers of several actors: one flat list of 3D labels, each prefixed by its
// actor (the AIM model's or skeleton's prefix), "Actor1_LFHD". The prefix is everything before
// the first '_', so a prefix holds none: a subject name's '_' becomes '-' ("85_02" streams as
// "85-02_LFHD"). A label without '_' belongs to no actor (subject "").

#include <string>
#include <string_view>

namespace skinstream::qtm {

std::string label_prefix(std::string_view subject_name);  // "85_02" -> "85-02"
std::string prefixed_label(std::string_view subject_name, std::string_view marker);  // "85-02_LFHD"

struct SplitLabel {
  std::string_view subject;  // "" when the label has no prefix
  std::string_view marker;
};
SplitLabel split_label(std::string_view label);

}  // namespace skinstream::qtm
