#include "server/control/control_request.h"

#include <algorithm>
#include <cctype>

#include "server/constant_time_equal.h"

namespace skinstream::server {
namespace {

ControlDecision refused_request(int status, std::string reason) {
  ControlDecision decision;
  decision.status = status;
  decision.reason = std::move(reason);
  return decision;
}

bool is_printable_operator(std::string_view name) {
  return name.size() <= kMaxControlOperatorBytes &&
         std::all_of(name.begin(), name.end(), [](char c) { return c >= 0x20 && c < 0x7f; });
}

bool is_blank_body(std::string_view body) {
  return std::all_of(body.begin(), body.end(),
                     [](char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; });
}

// The route of `path` for `method`, or the refusal: 404 when no route has the path, 405 (with the
// methods it has) when none has it for this method.
ControlDecision route_of(std::string_view method, std::string_view path) {
  ControlDecision decision;
  ControlPathParameters parameters;
  for (const ControlRoute& route : control_routes()) {
    if (!control_path_matches(route.pattern, path, parameters)) continue;
    if (route.method == method) {
      decision.route = &route;
      decision.parameters = std::move(parameters);
      return decision;
    }
    if (decision.allow.find(route.method) == std::string::npos)
      decision.allow += (decision.allow.empty() ? "" : ", ") + std::string(route.method);
  }
  if (decision.allow.empty()) return refused_request(404, "no such control route (docs/control-api.md)");
  decision.status = 405;
  decision.reason = "this control route takes " + decision.allow;
  return decision;
}

}  // namespace

std::string_view bearer_token(std::string_view authorization) {
  constexpr std::string_view kScheme = "bearer";
  if (authorization.size() <= kScheme.size()) return {};
  for (size_t i = 0; i < kScheme.size(); ++i)
    if (std::tolower(static_cast<unsigned char>(authorization[i])) != kScheme[i]) return {};
  if (authorization[kScheme.size()] != ' ') return {};
  std::string_view token = authorization.substr(kScheme.size());
  while (!token.empty() && token.front() == ' ') token.remove_prefix(1);
  while (!token.empty() && (token.back() == ' ' || token.back() == '\t')) token.remove_suffix(1);
  return token;
}

ControlDecision decide_control_request(const ControlRequest& request, std::string_view expected_token) {
  const std::string_view path = request.target.substr(0, request.target.find('?'));
  ControlDecision decision = route_of(request.method, path);
  if (decision.status != 200) return decision;

  // The token before anything else of the request is looked at: without it nothing more is told.
  const std::string_view token = bearer_token(request.authorization);
  if (token.empty()) return refused_request(401, "no token: send the header Authorization: Bearer TOKEN");
  if (!constant_time_equal(token, expected_token) || expected_token.empty())
    return refused_request(403, "wrong token");

  if (!is_printable_operator(request.operator_name))
    return refused_request(400, "X-Skinstream-Operator must be at most " +
                                    std::to_string(kMaxControlOperatorBytes) + " printable ASCII characters");
  if (request.body.size() > kMaxControlBodyBytes)
    return refused_request(413, "body of " + std::to_string(request.body.size()) + " bytes: at most " +
                                    std::to_string(kMaxControlBodyBytes));
  if (is_blank_body(request.body)) return decision;
  if (!decision.route->takes_body)
    return refused_request(400, std::string(decision.route->method) + " " +
                                    std::string(decision.route->pattern) + " takes no body");

  bool too_deep = false;
  const auto depth_check = [&too_deep](int depth, nlohmann::json::parse_event_t, nlohmann::json&) {
    if (depth > kMaxControlBodyDepth) too_deep = true;
    return !too_deep;
  };
  nlohmann::json body;
  try {
    body = nlohmann::json::parse(request.body, depth_check);
  } catch (const nlohmann::json::parse_error& e) {
    return refused_request(400, "body is not valid JSON (byte " + std::to_string(e.byte) + ")");
  } catch (const nlohmann::json::exception&) {
    // A number beyond a double (1e400) is out_of_range, not a parse_error.
    return refused_request(400, "body is not valid JSON (a number out of range)");
  }
  if (too_deep)
    return refused_request(400, "body nests deeper than " + std::to_string(kMaxControlBodyDepth) + " levels");
  if (!body.is_object()) return refused_request(400, "body must be a JSON object");
  decision.body = std::move(body);
  return decision;
}

}  // namespace skinstream::server
