#pragma once
// What one control request is, decided before anything is done: its route (or 404, 405), whether
// its token is right (401 without one, 403 when wrong) and its JSON body (400, 413). Plain strings
// in, a decision out: no socket, no Beast, so it is tested and fuzzed alone. The token is never
// put in a reason.

#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "server/control/control_routes.h"

namespace skinstream::server {

inline constexpr size_t kMaxControlBodyBytes = 16 * 1024;
inline constexpr size_t kMaxControlOperatorBytes = 64;
inline constexpr int kMaxControlBodyDepth = 16;  // nesting of the body's arrays and objects

struct ControlRequest {
  std::string_view method;         // "GET", "POST", ...
  std::string_view target;         // "/takes?x=1": the query is ignored
  std::string_view authorization;  // the Authorization header; "" when absent
  std::string_view operator_name;  // the X-Skinstream-Operator header; "" when absent
  std::string_view body;
};

struct ControlDecision {
  int status = 200;                     // 200: do `route`'s action; otherwise refused with this status
  const ControlRoute* route = nullptr;  // the matched route (set when status is 200)
  ControlPathParameters parameters;     // the route's "{name}" segments
  nlohmann::json body = nlohmann::json::object();  // the request's body: an object, {} when none
  std::string reason;                              // refused: one printable line, for the answer and the log
  std::string allow;                               // 405: the methods the path takes, "GET, POST"
};

// `expected_token` is the configured token (never empty when the control API is on; an empty one
// matches nothing).
ControlDecision decide_control_request(const ControlRequest& request, std::string_view expected_token);

// The token of "Bearer TOKEN" (the scheme in any case, then spaces); "" when there is none.
std::string_view bearer_token(std::string_view authorization);

}  // namespace skinstream::server
