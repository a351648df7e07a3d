#pragma once
// Every control request counted by what became of it, for /health (to_json) and /metrics
// (render_metrics: skinstream_control_requests_total{outcome="..."}). Any thread.

#include <atomic>
#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <string>

namespace skinstream::server {

struct ControlCounters {
  std::atomic<uint64_t> accepted{0};       // route, token and body right: the action was called
  std::atomic<uint64_t> refused_401{0};    // no token
  std::atomic<uint64_t> refused_403{0};    // a wrong token
  std::atomic<uint64_t> rate_limited{0};   // 429: too many wrong tokens from the address
  std::atomic<uint64_t> bad_request{0};    // 400, 413: the body or the operator's name
  std::atomic<uint64_t> unknown_route{0};  // 404, 405 on a control path

  // Counts a request by the status the control API decided on (not the action's).
  void count(int status);
  void render_metrics(std::string& out) const;
  nlohmann::json to_json() const;
};

}  // namespace skinstream::server
