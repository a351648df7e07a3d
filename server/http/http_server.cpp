#include "server/http/http_server.h"

#include <spdlog/spdlog.h>

#include <fstream>
#include <sstream>

#include "protocol/printable_text.h"
#include "server/beast.h"
#include "server/control/control_dispatch.h"
#include "server/control/control_request.h"
#include "server/http/query_parameter.h"
#include "server/http/static_files.h"
#include "server/http/websocket_subscriber.h"

namespace skinstream::server {
namespace {

// Refused WebSocket subscribers, all connections together: a flood logs once a second.
RateLimitedLog websocket_refusals;
// Refused control requests, all connections together: a flood of wrong tokens logs once a second.
RateLimitedLog control_refusals;

std::string remote_of(const tcp::socket& socket) {
  boost::system::error_code ec;
  const auto endpoint = socket.remote_endpoint(ec);
  return ec ? "?" : endpoint.address().to_string() + ":" + std::to_string(endpoint.port());
}

// One HTTP connection: requests one after another (keep-alive) until it upgrades or closes.
class HttpSession : public std::enable_shared_from_this<HttpSession> {
 public:
  HttpSession(asio::io_context& io, tcp::socket socket, std::shared_ptr<const HttpRoutes> routes,
              std::shared_ptr<ControlRateLimit> control_rate_limit)
      : io_(io),
        stream_(std::move(socket)),
        routes_(std::move(routes)),
        control_rate_limit_(std::move(control_rate_limit)) {}

  void read_next() {
    request_ = {};
    stream_.expires_after(std::chrono::seconds(30));
    http::async_read(stream_, buffer_, request_, [self = shared_from_this()](const boost::system::error_code& ec, size_t) {
      if (ec) return self->shutdown();
      self->handle();
    });
  }

 private:
  void handle() {
    const std::string target(request_.target());
    const std::string path = target.substr(0, target.find('?'));
    if (websocket::is_upgrade(request_)) {
      if (path != "/stream") return respond(error(http::status::not_found, "WebSocket subscribers connect to /stream\n"));
      return upgrade();
    }
    if (is_control_path(path)) {
      if (!routes_->control) return respond(error(http::status::not_found, "not found\n"));
      return control();
    }
    if (request_.method() != http::verb::get && request_.method() != http::verb::head)
      return respond(error(http::status::method_not_allowed, "only GET and HEAD\n"));
    if (path == "/health") return respond(text(routes_->health_json(), "application/json"));
    if (path == "/metrics") return respond(text(routes_->metrics_text(), "text/plain; version=0.0.4; charset=utf-8"));
    if (const auto file = resolve_static_file(routes_->web_root, target)) {
      std::ifstream in(*file, std::ios::binary);
      std::stringstream body;
      body << in.rdbuf();
      if (in) return respond(text(body.str(), content_type_for(*file)));
    }
    respond(error(http::status::not_found, "not found\n"));
  }

  // A WebSocket subscriber: admitted (allow-list, limits, the token on the URL) or told why not
  // in the HTTP status and a one-line body, and the connection closed.
  void upgrade() {
    SubscriberAdmission::Decision decision;
    std::shared_ptr<SubscriberAdmission> authenticate;
    tcp::endpoint peer;
    if (SubscriberAdmission* admission = routes_->stream_admission.get()) {
      boost::system::error_code ec;
      peer = stream_.socket().remote_endpoint(ec);
      if (ec) return shutdown();
      // With a token on the URL the subscriber is admitted now; without one it holds a place
      // kept for connections without the token until its Hello (version 2) carries it.
      std::optional<std::string> token;
      if (admission->token_required()) {
        token = query_parameter(std::string_view(request_.target().data(), request_.target().size()), "token");
        if (token && !admission->token_matches(*token)) return refuse(http::status::forbidden, "wrong token");
      }
      const bool unauthenticated = admission->token_required() && !token;
      decision = unauthenticated ? admission->admit_unauthenticated(peer.address()) : admission->admit(peer.address());
      if (decision.refusal != SubscriberAdmission::Refusal::None) {
        const bool not_allowed = decision.refusal == SubscriberAdmission::Refusal::NotAllowed;
        return refuse(not_allowed ? http::status::forbidden : http::status::service_unavailable, decision.reason);
      }
      if (unauthenticated) authenticate = routes_->stream_admission;
    }
    stream_.expires_never();
    tcp::socket socket = stream_.release_socket();
    const std::string remote = remote_of(socket);
    SubscriberHub& hub = routes_->stream_hub();
    auto subscriber = std::make_shared<WebSocketSubscriber>(io_, hub, std::move(socket), remote);
    subscriber->set_admission(std::move(decision), std::move(authenticate), peer.address());
    hub.add(subscriber);
    subscriber->accept(std::move(request_));
  }

  // A control request (docs/control-api.md): refused while its address is rate-limited, then
  // decided (route, token, body) and, when right, its action called. One log line each, naming the
  // peer and the operator, never the token.
  void control() {
    const ControlCaller caller{peer_address(), std::string(request_[operator_header()])};
    const std::string what =
        std::string(request_.method_string()) + " " +
        printable_text(std::string_view(request_.target().data(), request_.target().size()), 80);
    const std::string who = caller.address + " (operator " + quoted_text(caller.operator_name) + ")";
    ControlCounters& counters = *routes_->control_counters;
    const auto now = ControlRateLimit::Clock::now();
    if (const auto blocked = control_rate_limit_->blocked_for(caller.address, now); blocked.count() > 0) {
      counters.rate_limited.fetch_add(1, std::memory_order_relaxed);
      const auto seconds = std::chrono::ceil<std::chrono::seconds>(blocked).count();
      const std::string reason = "too many wrong tokens from " + caller.address + ": refused for " +
                                 std::to_string(seconds) + " s more";
      control_refusals.warn("control_refused", "control: " + what + " from " + who + ": 429 " + reason);
      auto res = json_answer(http::status::too_many_requests, {{"error", reason}});
      res.set(http::field::retry_after, std::to_string(seconds));
      return respond(std::move(res));
    }
    const ControlDecision decision =
        decide_control_request({.method = sv(request_.method_string()),
                                .target = sv(request_.target()),
                                .authorization = sv(request_[http::field::authorization]),
                                .operator_name = sv(request_[operator_header()]),
                                .body = request_.body()},
                               routes_->control_token);
    counters.count(decision.status);
    if (decision.status != 200) {
      std::string reason = decision.reason;
      if (decision.status == 403 && control_rate_limit_->count_refusal(caller.address, now))
        reason += "; too many from " + caller.address + ": refused for " +
                  std::to_string(
                      std::chrono::ceil<std::chrono::seconds>(routes_->control_rate_limit.block).count()) +
                  " s";
      control_refusals.warn("control_refused", "control: " + what + " from " + who + ": " +
                                                   std::to_string(decision.status) + " " + reason);
      auto res = json_answer(static_cast<http::status>(decision.status), {{"error", reason}});
      if (decision.status == 401) res.set(http::field::www_authenticate, "Bearer");
      if (decision.status == 405) res.set(http::field::allow, decision.allow);
      return respond(std::move(res));
    }
    ControlAnswer answer;
    try {
      answer = run_control_action(*routes_->control, decision, caller);
    } catch (const std::exception& e) {
      answer = {500, {{"error", printable_text(e.what())}}};
    }
    if (answer.status < 200 || answer.status > 599)
      answer = {500, {{"error", "the action answered no status"}}};
    spdlog::info("control: {} from {}: {}", what, who, answer.status);
    respond(json_answer(static_cast<http::status>(answer.status), answer.body));
  }

  static std::string_view sv(beast::string_view text) { return {text.data(), text.size()}; }
  static beast::string_view operator_header() { return "X-Skinstream-Operator"; }

  std::string peer_address() const {
    boost::system::error_code ec;
    const auto endpoint = stream_.socket().remote_endpoint(ec);
    return ec ? "?" : endpoint.address().to_string();
  }

  http::response<http::string_body> json_answer(http::status status, const nlohmann::json& body) {
    http::response<http::string_body> res{status, request_.version()};
    res.set(http::field::content_type, "application/json");
    res.set(http::field::cache_control, "no-store");
    res.body() = body.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
    return res;
  }

  void refuse(http::status status, const std::string& reason) {
    websocket_refusals.warn("websocket_refused", "WebSocket subscriber " + remote_of(stream_.socket()) + " refused: " + reason);
    auto res = error(status, reason + "\n");
    request_.keep_alive(false);
    respond(std::move(res));
  }

  http::response<http::string_body> text(std::string body, std::string_view type) {
    http::response<http::string_body> res{http::status::ok, request_.version()};
    res.set(http::field::content_type, std::string(type));
    res.set(http::field::cache_control, "no-store");
    res.body() = std::move(body);
    return res;
  }

  http::response<http::string_body> error(http::status status, std::string body) {
    http::response<http::string_body> res{status, request_.version()};
    res.set(http::field::content_type, "text/plain; charset=utf-8");
    res.body() = std::move(body);
    return res;
  }

  void respond(http::response<http::string_body> res) {
    res.keep_alive(request_.keep_alive());
    res.prepare_payload();
    if (request_.method() == http::verb::head) res.body().clear();
    response_ = std::make_shared<http::response<http::string_body>>(std::move(res));
    http::async_write(stream_, *response_, [self = shared_from_this()](const boost::system::error_code& ec, size_t) {
      if (ec || !self->response_->keep_alive()) return self->shutdown();
      self->response_.reset();
      self->read_next();
    });
  }

  void shutdown() {
    boost::system::error_code ignored;
    stream_.socket().shutdown(tcp::socket::shutdown_send, ignored);
  }

  asio::io_context& io_;
  beast::tcp_stream stream_;
  beast::flat_buffer buffer_;
  http::request<http::string_body> request_;
  std::shared_ptr<http::response<http::string_body>> response_;
  std::shared_ptr<const HttpRoutes> routes_;
  std::shared_ptr<ControlRateLimit> control_rate_limit_;
};

// The routes as the sessions read them: the control API's counters made when the daemon gave none.
std::shared_ptr<const HttpRoutes> checked_routes(HttpRoutes routes) {
  if (!routes.stream_hub)
    throw std::invalid_argument("the HTTP routes need the subscribers' hub (stream_hub)");
  if (routes.control && routes.control_token.empty())
    throw std::invalid_argument("the control API needs a token (control_token_file)");
  if (!routes.control_counters) routes.control_counters = std::make_shared<ControlCounters>();
  return std::make_shared<const HttpRoutes>(std::move(routes));
}

}  // namespace

HttpServer::HttpServer(asio::io_context& io, const std::string& address, int port, HttpRoutes routes,
                       ListenerOptions listening)
    : io_(io),
      routes_(checked_routes(std::move(routes))),
      control_rate_limit_(std::make_shared<ControlRateLimit>(routes_->control_rate_limit)),
      listener_(
          io, address, port, "HTTP port",
          [this](tcp::socket socket) {
            std::make_shared<HttpSession>(io_, std::move(socket), routes_, control_rate_limit_)->read_next();
          },
          std::move(listening)) {}

}  // namespace skinstream::server
