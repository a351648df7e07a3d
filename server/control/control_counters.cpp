#include "server/control/control_counters.h"

#include <nlohmann/json.hpp>
#include <utility>

namespace skinstream::server {
namespace {

using ControlCounterField = std::atomic<uint64_t> ControlCounters::*;
constexpr std::pair<const char*, ControlCounterField> kControlOutcomes[] = {
    {"accepted", &ControlCounters::accepted},       {"refused_401", &ControlCounters::refused_401},
    {"refused_403", &ControlCounters::refused_403}, {"rate_limited", &ControlCounters::rate_limited},
    {"bad_request", &ControlCounters::bad_request}, {"unknown_route", &ControlCounters::unknown_route},
};

}  // namespace

void ControlCounters::count(int status) {
  std::atomic<uint64_t>* counter = &bad_request;
  if (status >= 200 && status < 300)
    counter = &accepted;
  else if (status == 401)
    counter = &refused_401;
  else if (status == 403)
    counter = &refused_403;
  else if (status == 429)
    counter = &rate_limited;
  else if (status == 404 || status == 405)
    counter = &unknown_route;
  counter->fetch_add(1, std::memory_order_relaxed);
}

void ControlCounters::render_metrics(std::string& out) const {
  out += "# HELP skinstream_control_requests_total Control API requests (docs/control-api.md) by outcome.\n";
  out += "# TYPE skinstream_control_requests_total counter\n";
  for (const auto& [name, field] : kControlOutcomes)
    out += "skinstream_control_requests_total{outcome=\"" + std::string(name) + "\"} " +
           std::to_string((this->*field).load(std::memory_order_relaxed)) + "\n";
}

nlohmann::json ControlCounters::to_json() const {
  nlohmann::json json = nlohmann::json::object();
  for (const auto& [name, field] : kControlOutcomes)
    json[name] = (this->*field).load(std::memory_order_relaxed);
  return json;
}

}  // namespace skinstream::server
