// A control API request as skinstreamd decides it (decide_control_request): the input's first
// four lines are the method, the target, the Authorization and the X-Skinstream-Operator headers,
// the rest its body. Any request is accepted or refused with a one-line reason; an accepted one
// carried the token, names a route whose method it used, and holds a JSON object of at most
// 16 kB; a refusal never repeats the token.
#include <cstdlib>
#include <string>
#include <string_view>

#include "server/control/control_request.h"

namespace control = skinstream::server;

namespace {

constexpr std::string_view kFuzzToken = "fuzz-token-0123456789abcdef";

// A refusal's reason is one printable line (the answer's "error" and the log line carry it).
void expect_one_printable_reason(const std::string& reason) {
  if (reason.empty()) std::abort();
  for (const char c : reason)
    if (c < 0x20 || c == 0x7f) std::abort();
}

std::string_view next_line(std::string_view& input) {
  const size_t end = input.find('\n');
  const std::string_view line = input.substr(0, end);
  input.remove_prefix(end == std::string_view::npos ? input.size() : end + 1);
  return line;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string_view input(reinterpret_cast<const char*>(data), size);
  control::ControlRequest request;
  request.method = next_line(input);
  request.target = next_line(input);
  request.authorization = next_line(input);
  request.operator_name = next_line(input);
  request.body = input;
  const control::ControlDecision decision = control::decide_control_request(request, kFuzzToken);
  if (decision.status != 200) {
    expect_one_printable_reason(decision.reason);
    if (decision.route != nullptr) std::abort();
    if (decision.reason.find(kFuzzToken) != std::string::npos) std::abort();
    if (decision.status == 405 && decision.allow.empty()) std::abort();
    return 0;
  }
  if (decision.route == nullptr || decision.route->method != request.method) std::abort();
  if (control::bearer_token(request.authorization) != kFuzzToken) std::abort();
  if (!decision.body.is_object() || request.body.size() > control::kMaxControlBodyBytes) std::abort();
  return 0;
}
