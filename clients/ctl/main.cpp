// skinstream-ctl: the operator's control API of a skinstreamd (docs/control-api.md) from a
// script: start and stop takes, list them. Prints the daemon's JSON answer; exits 0 when it
// accepted, 1 when it refused (the one-line reason on stderr) or could not be reached, 2 on a
// usage error. The token comes from a file or SKINSTREAM_CONTROL_TOKEN, never from the command
// line, where ps shows it to every user.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "protocol/printable_text.h"
#include "server/beast.h"

namespace {

using namespace skinstream::server;

constexpr int kExitRefused = 1;
constexpr int kExitUsage = 2;
constexpr auto kControlTimeout = std::chrono::seconds(10);

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The token: the file's first line (trailing spaces and CR dropped), else the variable.
std::string control_token(const std::string& token_file) {
  if (!token_file.empty()) {
    std::ifstream in(token_file);
    std::string line;
    if (!in || !std::getline(in, line))
      throw UsageError(token_file + ": cannot read the token file, or it is empty");
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ' || line.back() == '\t'))
      line.pop_back();
    if (line.empty()) throw UsageError(token_file + ": the token file's first line is empty");
    return line;
  }
  if (const char* variable = std::getenv("SKINSTREAM_CONTROL_TOKEN"); variable && *variable) return variable;
  throw UsageError("no token: give --token-file FILE or set SKINSTREAM_CONTROL_TOKEN");
}

// One request and its answer, within kControlTimeout; throws std::runtime_error when the daemon
// cannot be reached or does not answer.
http::response<http::string_body> exchange(const std::string& host, int port,
                                           http::request<http::string_body> request) {
  asio::io_context io;
  tcp::resolver resolver(io);
  beast::tcp_stream stream(io);
  beast::flat_buffer buffer;
  http::response<http::string_body> response;
  boost::system::error_code failure;
  std::string failed_step;
  auto fail = [&](const boost::system::error_code& ec, const char* step) {
    failure = ec;
    failed_step = step;
  };
  stream.expires_after(kControlTimeout);
  resolver.async_resolve(
      host, std::to_string(port),
      [&](const boost::system::error_code& ec, tcp::resolver::results_type found) {
        if (ec) return fail(ec, "resolve");
        stream.async_connect(found, [&](const boost::system::error_code& ec, const tcp::endpoint&) {
          if (ec) return fail(ec, "connect to");
          http::async_write(stream, request, [&](const boost::system::error_code& ec, size_t) {
            if (ec) return fail(ec, "send to");
            http::async_read(stream, buffer, response, [&](const boost::system::error_code& ec, size_t) {
              if (ec) return fail(ec, "read the answer of");
            });
          });
        });
      });
  io.run();
  if (failure)
    throw std::runtime_error("cannot " + failed_step + " " + host + ":" + std::to_string(port) + ": " +
                             failure.message());
  return response;
}

// The reason a refusal gives: its JSON "error", else its body's first line, else the status.
std::string reason_of(const http::response<http::string_body>& response) {
  const nlohmann::json json = nlohmann::json::parse(response.body(), nullptr, false);
  if (json.is_object() && json.contains("error") && json["error"].is_string())
    return skinstream::printable_text(json["error"].get<std::string>());
  const std::string& body = response.body();
  const std::string first_line = body.substr(0, body.find('\n'));
  return skinstream::printable_text(first_line.empty() ? std::string(response.reason()) : first_line);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"skinstream-ctl: control a skinstreamd's takes (docs/control-api.md)"};
  std::string host = "127.0.0.1", token_file, operator_name, take_name;
  int port = 8480;
  if (const char* user = std::getenv("USER")) operator_name = user;
  app.add_option("--host", host, "the daemon's host (default 127.0.0.1)");
  app.add_option("--port", port, "its HTTP port (default 8480)")->check(CLI::Range(1, 65535));
  app.add_option("--token-file", token_file,
                 "a file whose first line is the control token (default: $SKINSTREAM_CONTROL_TOKEN)");
  app.add_option("--operator", operator_name, "who asks, for the daemon's log (default: $USER)");
  app.require_subcommand(1);
  CLI::App* take = app.add_subcommand("take", "start or stop a take");
  take->require_subcommand(1);
  CLI::App* start = take->add_subcommand("start", "start recording a take: take start [NAME]");
  start->add_option("name", take_name, "the take's name (default: the daemon's)");
  CLI::App* stop = take->add_subcommand("stop", "stop the take being recorded");
  CLI::App* takes = app.add_subcommand("takes", "list the takes");
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return kExitUsage;
  }

  http::request<http::string_body> request;
  request.version(11);
  if (start->parsed()) {
    request.method(http::verb::post);
    request.target("/takes");
    nlohmann::json body = nlohmann::json::object();
    if (!take_name.empty()) body["name"] = take_name;
    request.body() = body.dump();
    request.set(http::field::content_type, "application/json");
  } else if (stop->parsed()) {
    request.method(http::verb::post);
    request.target("/takes/stop");
  } else if (takes->parsed()) {
    request.method(http::verb::get);
    request.target("/takes");
  }
  try {
    request.set(http::field::authorization, "Bearer " + control_token(token_file));
  } catch (const UsageError& e) {
    std::fprintf(stderr, "skinstream-ctl: %s\n", e.what());
    return kExitUsage;
  }
  request.set(http::field::host, host);
  if (!operator_name.empty()) request.set("X-Skinstream-Operator", operator_name);
  request.keep_alive(false);
  request.prepare_payload();

  http::response<http::string_body> response;
  try {
    response = exchange(host, port, std::move(request));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "skinstream-ctl: %s\n", e.what());
    return kExitRefused;
  }
  const unsigned status = response.result_int();
  const nlohmann::json json = nlohmann::json::parse(response.body(), nullptr, false);
  if (!json.is_discarded()) std::cout << json.dump(2) << "\n";
  if (status >= 200 && status < 300) return 0;
  std::fprintf(stderr, "skinstream-ctl: %u %s\n", status, reason_of(response).c_str());
  return kExitRefused;
}
