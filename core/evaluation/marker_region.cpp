#include "core/evaluation/marker_region.h"

#include <algorithm>
#include <cctype>
#include <map>

namespace skinstream {

namespace {

std::string lower(std::string text) {
  for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return text;
}

// Plug-in Gait style codes after the side letter (L/R), lower case.
const std::map<std::string, std::string>& sided_codes() {
  static const std::map<std::string, std::string> codes = {
      {"fhd", "head"},      {"bhd", "head"},   {"bac", "torso"},   {"bak", "torso"},  {"sho", "shoulder"},
      {"upa", "upper_arm"}, {"elb", "elbow"},  {"frm", "forearm"}, {"wra", "hand"},   {"wrb", "hand"},
      {"wri", "hand"},      {"fin", "hand"},   {"hnd", "hand"},    {"fwt", "pelvis"}, {"bwt", "pelvis"},
      {"asi", "pelvis"},    {"psi", "pelvis"}, {"thi", "thigh"},   {"kne", "knee"},   {"shn", "shank"},
      {"tib", "shank"},     {"ank", "foot"},   {"hee", "foot"},    {"toe", "foot"},   {"mt1", "foot"},
      {"mt5", "foot"}};
  return codes;
}

const std::map<std::string, std::string>& unsided_codes() {
  static const std::map<std::string, std::string> codes = {
      {"c7", "torso"}, {"t10", "torso"}, {"clav", "torso"}, {"strn", "torso"}, {"sacr", "pelvis"}};
  return codes;
}

// Region words of grid names and their synonyms.
const std::map<std::string, std::string>& region_words() {
  static const std::map<std::string, std::string> words = {{"head", "head"},
                                                           {"torso", "torso"},
                                                           {"abdomen", "torso"},
                                                           {"belly", "torso"},
                                                           {"chest", "torso"},
                                                           {"back", "torso"},
                                                           {"neck", "torso"},
                                                           {"shoulder", "shoulder"},
                                                           {"upper_arm", "upper_arm"},
                                                           {"upperarm", "upper_arm"},
                                                           {"elbow", "elbow"},
                                                           {"forearm", "forearm"},
                                                           {"wrist", "hand"},
                                                           {"hand", "hand"},
                                                           {"pelvis", "pelvis"},
                                                           {"hip", "pelvis"},
                                                           {"thigh", "thigh"},
                                                           {"knee", "knee"},
                                                           {"shank", "shank"},
                                                           {"shin", "shank"},
                                                           {"calf", "shank"},
                                                           {"ankle", "foot"},
                                                           {"foot", "foot"},
                                                           {"heel", "foot"},
                                                           {"toe", "foot"}};
  return words;
}

bool all_digits(const std::string& text) {
  return !text.empty() && std::all_of(text.begin(), text.end(),
                                      [](char c) { return std::isdigit(static_cast<unsigned char>(c)); });
}

std::string grid_region(std::string name) {
  // "<region>_<n>" (or "<region>_<n>_<m>"): drop the indices, then an optional side prefix.
  bool indexed = false;
  for (size_t underscore = name.rfind('_');
       underscore != std::string::npos && all_digits(name.substr(underscore + 1));
       underscore = name.rfind('_')) {
    name.resize(underscore);
    indexed = true;
  }
  if (!indexed) return {};
  for (const char* side : {"left_", "right_", "l_", "r_"}) {
    const std::string prefix = side;
    if (name.rfind(prefix, 0) == 0) {
      const auto it = region_words().find(name.substr(prefix.size()));
      if (it != region_words().end()) return it->second;
    }
  }
  const auto it = region_words().find(name);
  return it == region_words().end() ? std::string{} : it->second;
}

}  // namespace

const std::vector<std::string>& marker_regions() {
  static const std::vector<std::string> regions = {"head",    "torso", "shoulder", "upper_arm", "elbow",
                                                   "forearm", "hand",  "pelvis",   "thigh",     "knee",
                                                   "shank",   "foot",  "other"};
  return regions;
}

std::string marker_region(const std::string& label) {
  std::string name = lower(label.substr(label.rfind(':') == std::string::npos ? 0 : label.rfind(':') + 1));
  for (char& c : name)
    if (c == ' ' || c == '-') c = '_';
  if (name.empty()) return "other";

  if (const std::string region = grid_region(name); !region.empty()) return region;
  if (const auto it = region_words().find(name); it != region_words().end()) return it->second;
  if (const auto it = unsided_codes().find(name); it != unsided_codes().end()) return it->second;
  if (name[0] == 'l' || name[0] == 'r') {
    if (const auto it = sided_codes().find(name.substr(1)); it != sided_codes().end()) return it->second;
  }
  return "other";
}

}  // namespace skinstream
