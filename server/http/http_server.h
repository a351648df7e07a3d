#pragma once
// The daemon's HTTP port (Boost.Beast): /health (JSON), /metrics (Prometheus text), WebSocket
// subscribers at /stream, static files from the web root at /, 404 otherwise.

#include <filesystem>
#include <functional>
#include <memory>
#include <string>

#include "server/listener.h"
#include "server/publish/subscriber_admission.h"
#include "server/publish/subscriber_hub.h"

namespace skinstream::server {

struct HttpRoutes {
  std::function<std::string()> health_json;
  std::function<std::string()> metrics_text;
  std::filesystem::path web_root;  // empty: no static files
  // Who may open /stream (refused: 403 or 503 with the reason); null: anyone.
  std::shared_ptr<SubscriberAdmission> stream_admission;
};

class HttpServer {
 public:
  // `listening.tcp_congestion`: set on every connection, so WebSocket subscribers get it.
  HttpServer(asio::io_context& io, const std::string& address, int port, SubscriberHub& hub, HttpRoutes routes,
             ListenerOptions listening = {});
  void start() { listener_.start(); }
  void stop() { listener_.stop(); }
  int port() const { return listener_.port(); }

 private:
  asio::io_context& io_;
  SubscriberHub& hub_;
  std::shared_ptr<const HttpRoutes> routes_;
  Listener listener_;
};

}  // namespace skinstream::server
