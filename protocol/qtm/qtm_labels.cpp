#include "protocol/qtm/qtm_labels.h"

#include <algorithm>

namespace skinstream::qtm {

std::string label_prefix(std::string_view subject_name) {
  std::string prefix(subject_name);
  std::replace(prefix.begin(), prefix.end(), '_', '-');
  return prefix;
}

std::string prefixed_label(std::string_view subject_name, std::string_view marker) {
  if (subject_name.empty()) return std::string(marker);
  return label_prefix(subject_name) + "_" + std::string(marker);
}

SplitLabel split_label(std::string_view label) {
  const size_t underscore = label.find('_');
  if (underscore == std::string_view::npos || underscore == 0) return {{}, label};
  return {label.substr(0, underscore), label.substr(underscore + 1)};
}

}  // namespace skinstream::qtm
