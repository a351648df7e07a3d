#pragma once
// The check of a function's inputs that names what it guards. A file declares one for itself,
// named for the file (a unity build compiles several files as one),
//   constexpr Precondition require_joints{"part joints"};
// and require_joints(m > 0, "no markers") then throws std::invalid_argument("part joints: no markers").
#include <stdexcept>
#include <string>
#include <string_view>

namespace skinstream {

struct Precondition {
  std::string_view component;  // the message prefix

  // Throws std::invalid_argument("<component>: <what>") unless ok.
  void operator()(bool ok, std::string_view what) const {
    if (!ok) throw std::invalid_argument(std::string(component) + ": " + std::string(what));
  }
};

}  // namespace skinstream
