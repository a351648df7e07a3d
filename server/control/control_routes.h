#pragma once
// The control API's routes, one line each (control_routes.cpp). A pattern's "{name}" segment
// matches any one non-empty segment, handed to the action as a parameter: a later
// "DELETE /subjects/{name}" is one more line here, one more ControlAction and its call
// (control_dispatch.cpp).

#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace skinstream::server {

enum class ControlAction {
  StartTake,
  StopTake,
  ListTakes,
  CalibrateSubject,
  LoadSubjectFile,
  AddSubject,
  RemoveSubject,
  SubjectState,
  ListSubjects
};

struct ControlRoute {
  std::string_view method;   // "GET", "POST", "DELETE"
  std::string_view pattern;  // "/takes/stop", "/subjects/{name}"
  ControlAction action;
  bool takes_body = false;  // a JSON object body is accepted (otherwise a body is refused)
};

std::span<const ControlRoute> control_routes();

// The "{name}" segments of a matched pattern, in order: {"name", "Actor1"}.
using ControlPathParameters = std::vector<std::pair<std::string, std::string>>;

// Whether `path` (no query) matches `pattern`; fills `out_parameters` when it does.
bool control_path_matches(std::string_view pattern, std::string_view path,
                          ControlPathParameters& out_parameters);

// Whether `path` is the control API's (its first segment is a route's first segment, "/takes"):
// such paths are answered by the control API alone, never by static files.
bool is_control_path(std::string_view path);

}  // namespace skinstream::server
