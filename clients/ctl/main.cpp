// skinstream-ctl: the operator's control API of a skinstreamd (docs/control-api.md) from a
// script: start and stop takes, list them; calibrate a subject live or load another subject
// file into it, and wait for the swap. Prints the daemon's JSON answer; exits 0 when it
// accepted (and a subject change succeeded), 1 when it refused or the change failed (the
// one-line reason on stderr) or it could not be reached, 2 on a usage error. The token comes from a file or
// SKINSTREAM_CONTROL_TOKEN, never from the command line, where ps shows it to every user.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <thread>

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

struct Control {
  std::string host;
  int port = 0;
  std::string token, operator_name;

  // One request; its status and JSON body (null when the body is not JSON). Throws
  // std::runtime_error when the daemon cannot be reached.
  std::pair<unsigned, nlohmann::json> call(http::verb method, const std::string& target,
                                           const nlohmann::json* body, std::string* reason) const {
    http::request<http::string_body> request;
    request.version(11);
    request.method(method);
    request.target(target);
    if (body) {
      request.body() = body->dump();
      request.set(http::field::content_type, "application/json");
    }
    request.set(http::field::authorization, "Bearer " + token);
    request.set(http::field::host, host);
    if (!operator_name.empty()) request.set("X-Skinstream-Operator", operator_name);
    request.keep_alive(false);
    request.prepare_payload();
    const http::response<http::string_body> response = exchange(host, port, std::move(request));
    if (reason) *reason = reason_of(response);
    const nlohmann::json json = nlohmann::json::parse(response.body(), nullptr, false);
    return {response.result_int(), json.is_discarded() ? nlohmann::json() : json};
  }
};

// A subject change asked for: polls GET /subjects/NAME until it is done or failed (or `limit`
// passes), prints its last state; 0 when done.
int wait_for_change(const Control& control, const std::string& name, std::chrono::seconds limit) {
  const auto until = std::chrono::steady_clock::now() + limit;
  nlohmann::json change;
  for (;;) {
    std::this_thread::sleep_for(std::chrono::milliseconds(250));
    std::string reason;
    const auto [status, json] = control.call(http::verb::get, "/subjects/" + name, nullptr, &reason);
    if (status != 200) {
      std::fprintf(stderr, "skinstream-ctl: %u %s\n", status, reason.c_str());
      return kExitRefused;
    }
    change = json.value("change", nlohmann::json());
    const std::string state = change.is_object() ? change.value("state", "") : "";
    if (state == "done" || state == "failed") break;
    if (std::chrono::steady_clock::now() > until) {
      std::fprintf(stderr, "skinstream-ctl: subject %s: still %s after %lld s; not waiting longer\n",
                   name.c_str(), state.c_str(), static_cast<long long>(limit.count()));
      return kExitRefused;
    }
  }
  std::cout << change.dump(2) << "\n";
  if (change.value("state", "") == "done") return 0;
  std::fprintf(stderr, "skinstream-ctl: subject %s: %s failed: %s\n", name.c_str(),
               change.value("kind", "change").c_str(),
               skinstream::printable_text(change.value("reason", "")).c_str());
  return kExitRefused;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"skinstream-ctl: control a skinstreamd's takes and subjects (docs/control-api.md)"};
  Control control{"127.0.0.1", 8480, "", ""};
  std::string token_file, take_name, subject_name, subject_file, mesh;
  double seconds = 30.0;
  bool no_wait = false;
  if (const char* user = std::getenv("USER")) control.operator_name = user;
  app.add_option("--host", control.host, "the daemon's host (default 127.0.0.1)");
  app.add_option("--port", control.port, "its HTTP port (default 8480)")->check(CLI::Range(1, 65535));
  app.add_option("--token-file", token_file,
                 "a file whose first line is the control token (default: $SKINSTREAM_CONTROL_TOKEN)");
  app.add_option("--operator", control.operator_name, "who asks, for the daemon's log (default: $USER)");
  app.require_subcommand(1);
  CLI::App* take = app.add_subcommand("take", "start or stop a take");
  take->require_subcommand(1);
  CLI::App* start = take->add_subcommand("start", "start recording a take: take start [NAME]");
  start->add_option("name", take_name, "the take's name (default: the daemon's)");
  CLI::App* stop = take->add_subcommand("stop", "stop the take being recorded");
  CLI::App* takes = app.add_subcommand("takes", "list the takes");
  CLI::App* subject =
      app.add_subcommand("subject", "calibrate a subject live, or give it another subject file");
  subject->require_subcommand(1);
  CLI::App* calibrate = subject->add_subcommand(
      "calibrate",
      "record the subject's range of motion from the stream, build it, check it, swap it in: calibrate NAME");
  calibrate->add_option("name", subject_name, "the subject")->required();
  calibrate->add_option("--seconds", seconds, "seconds of range of motion to record (default 30)")
      ->check(CLI::Range(1.0, 120.0));
  calibrate->add_option("--mesh", mesh, "the body to fit (default: the daemon's calibration_mesh)");
  CLI::App* load =
      subject->add_subcommand("load", "serve the subject from another subject file: load NAME FILE");
  load->add_option("name", subject_name, "the subject")->required();
  load->add_option("file", subject_file, "the subject file (a path on the daemon's machine)")->required();
  CLI::App* add = subject->add_subcommand("add", "serve another subject from a subject file: add NAME FILE");
  add->add_option("name", subject_name, "the source's name of the subject")->required();
  add->add_option("file", subject_file, "the subject file (a path on the daemon's machine)")->required();
  CLI::App* remove =
      subject->add_subcommand("remove", "stop serving a subject (its subscribers are told): remove NAME");
  remove->add_option("name", subject_name, "the subject")->required();
  for (CLI::App* change : {calibrate, load, add})
    change->add_flag("--no-wait", no_wait, "return once the daemon accepted, without waiting for the swap");
  CLI::App* subjects = app.add_subcommand("subjects", "list the subjects and their last change");
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return kExitUsage;
  }
  try {
    control.token = control_token(token_file);
  } catch (const UsageError& e) {
    std::fprintf(stderr, "skinstream-ctl: %s\n", e.what());
    return kExitUsage;
  }

  http::verb method = http::verb::get;
  std::string target;
  nlohmann::json body = nlohmann::json::object();
  bool has_body = false;
  if (start->parsed()) {
    method = http::verb::post, target = "/takes", has_body = true;
    if (!take_name.empty()) body["name"] = take_name;
  } else if (stop->parsed()) {
    method = http::verb::post, target = "/takes/stop";
  } else if (takes->parsed()) {
    target = "/takes";
  } else if (calibrate->parsed()) {
    method = http::verb::post, target = "/subjects/" + subject_name + "/calibration", has_body = true;
    body["seconds"] = seconds;
    if (!mesh.empty()) body["mesh"] = mesh;
  } else if (load->parsed()) {
    method = http::verb::post, target = "/subjects/" + subject_name + "/file", has_body = true;
    body["file"] = subject_file;
  } else if (add->parsed()) {
    method = http::verb::post, target = "/subjects", has_body = true;
    body["name"] = subject_name;
    body["file"] = subject_file;
  } else if (remove->parsed()) {
    method = http::verb::delete_, target = "/subjects/" + subject_name;
  } else if (subjects->parsed()) {
    target = "/subjects";
  }
  try {
    std::string reason;
    const auto [status, json] = control.call(method, target, has_body ? &body : nullptr, &reason);
    if (status < 200 || status >= 300) {
      if (!json.is_null()) std::cout << json.dump(2) << "\n";
      std::fprintf(stderr, "skinstream-ctl: %u %s\n", status, reason.c_str());
      return kExitRefused;
    }
    const bool change = calibrate->parsed() || load->parsed() || add->parsed();
    if (!change || no_wait) {
      if (!json.is_null()) std::cout << json.dump(2) << "\n";
      return 0;
    }
    // Recording, then the build (real actors: under a minute), then the swap.
    return wait_for_change(control, subject_name, std::chrono::seconds(static_cast<long>(seconds) + 900));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "skinstream-ctl: %s\n", e.what());
    return kExitRefused;
  }
}
