#pragma once
// The daemon's HTTP port (Boost.Beast): /health (JSON), /metrics (Prometheus text), WebSocket
// subscribers at /stream, static files from the web root at /, the operator's control API
// (docs/control-api.md: /takes ...) when it is on, 404 otherwise.

#include <filesystem>
#include <functional>
#include <memory>
#include <string>

#include "server/control/control_actions.h"
#include "server/control/control_counters.h"
#include "server/control/control_rate_limit.h"
#include "server/listener.h"
#include "server/publish/subscriber_admission.h"
#include "server/publish/subscriber_hub.h"

namespace skinstream::server {

struct HttpRoutes {
  // The io thread, for each WebSocket subscriber: the hub it starts in (the first subject's; its
  // Hello may name another). Subjects come and go at run time, so it is asked each time.
  std::function<SubscriberHub&()> stream_hub;
  std::function<std::string()> health_json;
  std::function<std::string()> metrics_text;
  std::filesystem::path web_root;  // empty: no static files
  // Who may open /stream (refused: 403 or 503 with the reason); null: anyone.
  std::shared_ptr<SubscriberAdmission> stream_admission;
  // The control API: null = off (its paths answer 404, POST anywhere 405). On, it needs the token
  // (load_control_token, server/control/control_token.h), which is never logged nor echoed.
  std::shared_ptr<ControlActions> control;
  std::string control_token;
  // Its requests counted, for /health and /metrics; null: the server makes its own (control_counters()).
  std::shared_ptr<ControlCounters> control_counters;
  ControlRateLimitOptions control_rate_limit;
};

class HttpServer {
 public:
  // `listening.tcp_congestion`: set on every connection, so WebSocket subscribers get it.
  // Throws std::invalid_argument for a control API without a token.
  // Throws std::invalid_argument for routes without a stream_hub.
  HttpServer(asio::io_context& io, const std::string& address, int port, HttpRoutes routes,
             ListenerOptions listening = {});
  void start() { listener_.start(); }
  void stop() { listener_.stop(); }
  int port() const { return listener_.port(); }
  const ControlCounters& control_counters() const { return *routes_->control_counters; }

 private:
  asio::io_context& io_;
  std::shared_ptr<const HttpRoutes> routes_;
  std::shared_ptr<ControlRateLimit> control_rate_limit_;
  Listener listener_;
};

}  // namespace skinstream::server
