#include "server/control/control_routes.h"

#include <algorithm>

namespace skinstream::server {
namespace {

constexpr ControlRoute kControlRoutes[] = {
    {"GET", "/takes", ControlAction::ListTakes},
    {"POST", "/takes", ControlAction::StartTake, /*takes_body=*/true},
    {"POST", "/takes/stop", ControlAction::StopTake},
    {"GET", "/subjects", ControlAction::ListSubjects},
    {"POST", "/subjects", ControlAction::AddSubject, /*takes_body=*/true},
    {"GET", "/subjects/{name}", ControlAction::SubjectState},
    {"DELETE", "/subjects/{name}", ControlAction::RemoveSubject},
    {"POST", "/subjects/{name}/calibration", ControlAction::CalibrateSubject, /*takes_body=*/true},
    {"POST", "/subjects/{name}/file", ControlAction::LoadSubjectFile, /*takes_body=*/true},
};

// The next segment of `path` after position `at` (which is at a '/'), advancing `at` past it.
std::string_view next_route_segment(std::string_view path, size_t& at) {
  if (at >= path.size() || path[at] != '/') return {};
  const size_t start = at + 1;
  const size_t end = std::min(path.find('/', start), path.size());
  at = end;
  return path.substr(start, end - start);
}

std::string_view first_route_segment(std::string_view path) {
  size_t at = 0;
  return next_route_segment(path, at);
}

}  // namespace

std::span<const ControlRoute> control_routes() { return kControlRoutes; }

bool control_path_matches(std::string_view pattern, std::string_view path,
                          ControlPathParameters& out_parameters) {
  out_parameters.clear();
  size_t at_pattern = 0, at_path = 0;
  while (at_pattern < pattern.size() || at_path < path.size()) {
    if (at_pattern >= pattern.size() || at_path >= path.size() || path[at_path] != '/') return false;
    const std::string_view want = next_route_segment(pattern, at_pattern);
    const std::string_view have = next_route_segment(path, at_path);
    if (want.size() > 2 && want.front() == '{' && want.back() == '}') {
      if (have.empty()) return false;
      out_parameters.emplace_back(want.substr(1, want.size() - 2), have);
    } else if (want != have) {
      return false;
    }
  }
  return true;
}

bool is_control_path(std::string_view path) {
  const std::string_view first = first_route_segment(path);
  if (first.empty()) return false;
  for (const ControlRoute& route : kControlRoutes)
    if (first_route_segment(route.pattern) == first) return true;
  return false;
}

}  // namespace skinstream::server
