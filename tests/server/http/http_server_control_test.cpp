// The control API through a real HttpServer on loopback, with a ControlActions double that
// records its calls: who may call what, what is answered, what is counted.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "server/beast.h"
#include "server/http/http_server.h"
#include "support/io_thread.h"
#include "support/test_data.h"

namespace skinstream::server {
namespace {

const std::string kControlToken = "stage-token-0123456789";

// The daemon's side, recorded: which action was called, by whom, with what.
class RecordingControlActions : public ControlActions {
 public:
  struct Call {
    std::string action;
    ControlCaller caller;
    nlohmann::json request;
  };
  ControlAnswer start_take(const ControlCaller& caller, const nlohmann::json& request) override {
    record({"start_take", caller, request});
    return {201, {{"take", request.value("name", "take-1")}, {"recording", true}}};
  }
  ControlAnswer stop_take(const ControlCaller& caller) override {
    record({"stop_take", caller, {}});
    return {409, {{"error", "no take is being recorded"}}};
  }
  ControlAnswer list_takes() override {
    record({"list_takes", {}, {}});
    return {200, {{"takes", nlohmann::json::array({"a", "b"})}}};
  }
  ControlAnswer calibrate_subject(const ControlCaller& caller, const std::string& name,
                                  const nlohmann::json& request) override {
    record({"calibrate_subject:" + name, caller, request});
    return {202, {{"state", "recording"}}};
  }
  ControlAnswer load_subject_file(const ControlCaller& caller, const std::string& name,
                                  const nlohmann::json& request) override {
    record({"load_subject_file:" + name, caller, request});
    return {202, {{"state", "loading"}}};
  }
  ControlAnswer add_subject(const ControlCaller& caller, const nlohmann::json& request) override {
    record({"add_subject", caller, request});
    return {202, {{"state", "loading"}}};
  }
  ControlAnswer remove_subject(const ControlCaller& caller, const std::string& name) override {
    record({"remove_subject:" + name, caller, {}});
    return {200, {{"removed", name}}};
  }
  ControlAnswer subject_state(const std::string& name) override {
    record({"subject_state:" + name, {}, {}});
    return {200, {{"name", name}}};
  }
  ControlAnswer list_subjects() override {
    record({"list_subjects", {}, {}});
    return {200, {{"subjects", nlohmann::json::array()}}};
  }
  std::vector<Call> calls() {
    std::lock_guard lock(mutex_);
    return calls_;
  }

 private:
  void record(Call call) {
    std::lock_guard lock(mutex_);
    calls_.push_back(std::move(call));
  }
  std::mutex mutex_;
  std::vector<Call> calls_;
};

struct Answer {
  int status = 0;
  std::string www_authenticate, allow, cache_control, content_type;
  std::string body;
  nlohmann::json json() const { return nlohmann::json::parse(body); }
};

// One request on its own connection.
Answer send(int port, http::verb method, const std::string& target, const std::string& authorization = "",
            const std::string& body = "", const std::string& operator_name = "") {
  asio::io_context io;
  beast::tcp_stream stream(io);
  stream.connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), static_cast<unsigned short>(port)));
  http::request<http::string_body> request{method, target, 11};
  request.set(http::field::host, "127.0.0.1");
  if (!authorization.empty()) request.set(http::field::authorization, authorization);
  if (!operator_name.empty()) request.set("X-Skinstream-Operator", operator_name);
  request.body() = body;
  request.prepare_payload();
  http::write(stream, request);
  beast::flat_buffer buffer;
  http::response<http::string_body> response;
  http::read(stream, buffer, response);
  return {
      static_cast<int>(response.result_int()),          std::string(response[http::field::www_authenticate]),
      std::string(response[http::field::allow]),        std::string(response[http::field::cache_control]),
      std::string(response[http::field::content_type]), response.body()};
}

class HttpServerControl : public ::testing::Test {
 protected:
  void start(bool control_on) {
    HttpRoutes routes;
    routes.health_json = [] { return std::string("{}"); };
    routes.metrics_text = [] { return std::string(); };
    if (control_on) {
      routes.control = actions;
      routes.control_token = kControlToken;
      routes.control_counters = counters;
      routes.control_rate_limit = {.max_refusals = 5,
                                   .window = std::chrono::seconds(10),
                                   .block = std::chrono::seconds(60),
                                   .max_addresses = 16};
    }
    server = io_thread.call([&] {
      routes.stream_hub = [this]() -> SubscriberHub& { return hub; };
      auto made = std::make_unique<HttpServer>(io_thread.io, "127.0.0.1", 0, std::move(routes));
      made->start();
      return made;
    });
    port = server->port();
  }
  void TearDown() override {
    if (server)
      io_thread.call([&] {
        server->stop();
        return 0;
      });
  }

  Metrics metrics;
  SubscriberHub hub{metrics, HubOptions{}, {}, false};
  std::shared_ptr<RecordingControlActions> actions = std::make_shared<RecordingControlActions>();
  std::shared_ptr<ControlCounters> counters = std::make_shared<ControlCounters>();
  test::IoThread io_thread;
  std::unique_ptr<HttpServer> server;
  int port = 0;
};

TEST_F(HttpServerControl, WithoutATokenConfiguredControlPathsAre404AndNothingIsCalled) {
  start(false);
  EXPECT_EQ(send(port, http::verb::post, "/takes", "Bearer " + kControlToken, "{}").status, 404);
  EXPECT_EQ(send(port, http::verb::post, "/takes/stop", "Bearer " + kControlToken).status, 404);
  EXPECT_EQ(send(port, http::verb::get, "/takes", "Bearer " + kControlToken).status, 404);
  EXPECT_EQ(send(port, http::verb::post, "/health").status, 405);
  EXPECT_TRUE(actions->calls().empty());
}

TEST_F(HttpServerControl, WithoutAuthorizationItIs401AskingForABearerToken) {
  start(true);
  const Answer answer = send(port, http::verb::post, "/takes/stop");
  EXPECT_EQ(answer.status, 401);
  EXPECT_EQ(answer.www_authenticate, "Bearer");
  EXPECT_FALSE(answer.json().at("error").get<std::string>().empty());
  EXPECT_TRUE(actions->calls().empty());
  EXPECT_EQ(counters->refused_401.load(), 1u);
  EXPECT_EQ(counters->accepted.load(), 0u);
}

TEST_F(HttpServerControl, AWrongTokenIs403CountedAndNothingIsCalled) {
  start(true);
  const Answer answer =
      send(port, http::verb::post, "/takes", "Bearer " + kControlToken + "0", R"({"name":"x"})");
  EXPECT_EQ(answer.status, 403);
  EXPECT_EQ(answer.cache_control, "no-store");
  EXPECT_EQ(answer.body.find(kControlToken), std::string::npos);
  EXPECT_TRUE(actions->calls().empty());
  EXPECT_EQ(counters->refused_403.load(), 1u);
  std::string metrics_text;
  counters->render_metrics(metrics_text);
  EXPECT_NE(metrics_text.find("skinstream_control_requests_total{outcome=\"refused_403\"} 1\n"),
            std::string::npos)
      << metrics_text;
  EXPECT_EQ(counters->to_json().at("refused_403"), 1);
}

TEST_F(HttpServerControl, TheRightTokenCallsTheActionWithTheCallerAndAnswersItsJson) {
  start(true);
  const Answer started =
      send(port, http::verb::post, "/takes", "Bearer " + kControlToken, R"({"name":"take 7"})", "anna");
  EXPECT_EQ(started.status, 201);
  EXPECT_EQ(started.content_type, "application/json");
  EXPECT_EQ(started.cache_control, "no-store");
  EXPECT_EQ(started.json().at("take"), "take 7");
  const Answer stopped = send(port, http::verb::post, "/takes/stop", "Bearer " + kControlToken, "", "bob");
  EXPECT_EQ(stopped.status, 409);
  EXPECT_EQ(stopped.json().at("error"), "no take is being recorded");
  const Answer listed = send(port, http::verb::get, "/takes", "Bearer " + kControlToken);
  EXPECT_EQ(listed.status, 200);
  EXPECT_EQ(listed.json().at("takes").size(), 2u);

  const std::vector<RecordingControlActions::Call> calls = actions->calls();
  ASSERT_EQ(calls.size(), 3u);
  EXPECT_EQ(calls[0].action, "start_take");
  EXPECT_EQ(calls[0].caller.address, "127.0.0.1");
  EXPECT_EQ(calls[0].caller.operator_name, "anna");
  EXPECT_EQ(calls[0].request.at("name"), "take 7");
  EXPECT_EQ(calls[1].action, "stop_take");
  EXPECT_EQ(calls[1].caller.operator_name, "bob");
  EXPECT_EQ(calls[2].action, "list_takes");
  EXPECT_EQ(counters->accepted.load(), 3u);
}

TEST_F(HttpServerControl, TheSubjectRoutesCallTheirActionWithTheSubjectNamedInThePath) {
  start(true);
  const std::string bearer = "Bearer " + kControlToken;
  EXPECT_EQ(send(port, http::verb::post, "/subjects/Actor2/calibration", bearer, R"({"seconds":30})").status,
            202);
  EXPECT_EQ(send(port, http::verb::post, "/subjects/Actor1/file", bearer, R"({"file":"a.sksubj"})").status,
            202);
  EXPECT_EQ(send(port, http::verb::get, "/subjects/Actor1", bearer).json().at("name"), "Actor1");
  EXPECT_EQ(send(port, http::verb::get, "/subjects", bearer).status, 200);
  EXPECT_EQ(
      send(port, http::verb::post, "/subjects", bearer, R"({"name":"Actor3","file":"c.sksubj"})").status,
      202);
  EXPECT_EQ(send(port, http::verb::delete_, "/subjects/Actor3", bearer).json().at("removed"), "Actor3");
  EXPECT_EQ(send(port, http::verb::get, "/subjects/Actor1/calibration", bearer).status, 405);
  EXPECT_EQ(send(port, http::verb::post, "/subjects/Actor1/other", bearer).status, 404);
  const std::vector<RecordingControlActions::Call> calls = actions->calls();
  ASSERT_EQ(calls.size(), 6u);
  EXPECT_EQ(calls[0].action, "calibrate_subject:Actor2");
  EXPECT_EQ(calls[0].request.at("seconds"), 30);
  EXPECT_EQ(calls[1].action, "load_subject_file:Actor1");
  EXPECT_EQ(calls[1].request.at("file"), "a.sksubj");
  EXPECT_EQ(calls[2].action, "subject_state:Actor1");
  EXPECT_EQ(calls[3].action, "list_subjects");
  EXPECT_EQ(calls[4].action, "add_subject");
  EXPECT_EQ(calls[4].request.at("name"), "Actor3");
  EXPECT_EQ(calls[5].action, "remove_subject:Actor3");
}

TEST_F(HttpServerControl, BadRequestsAreRefusedBeforeTheAction) {
  start(true);
  EXPECT_EQ(send(port, http::verb::post, "/takes", "Bearer " + kControlToken, "{oops").status, 400);
  EXPECT_EQ(
      send(port, http::verb::post, "/takes", "Bearer " + kControlToken, std::string(20'000, ' ')).status,
      413);
  const Answer wrong_method = send(port, http::verb::get, "/takes/stop", "Bearer " + kControlToken);
  EXPECT_EQ(wrong_method.status, 405);
  EXPECT_EQ(wrong_method.allow, "POST");
  EXPECT_EQ(send(port, http::verb::post, "/takes/other", "Bearer " + kControlToken).status, 404);
  // Other paths stay GET and HEAD only.
  EXPECT_EQ(send(port, http::verb::post, "/health", "Bearer " + kControlToken).status, 405);
  EXPECT_TRUE(actions->calls().empty());
  EXPECT_EQ(counters->bad_request.load(), 2u);
  EXPECT_EQ(counters->unknown_route.load(), 2u);
}

TEST_F(HttpServerControl, AFloodOfWrongTokensIsRateLimitedEvenForTheRightOne) {
  start(true);
  for (int i = 0; i < 5; ++i)
    EXPECT_EQ(send(port, http::verb::get, "/takes", "Bearer guess-" + std::to_string(i)).status, 403);
  const Answer limited = send(port, http::verb::get, "/takes", "Bearer guess-5");
  EXPECT_EQ(limited.status, 429);
  // Once blocked, the right token waits too: a guess that happens to be right gains nothing.
  EXPECT_EQ(send(port, http::verb::get, "/takes", "Bearer " + kControlToken).status, 429);
  EXPECT_TRUE(actions->calls().empty());
  EXPECT_EQ(counters->refused_403.load(), 5u);
  EXPECT_EQ(counters->rate_limited.load(), 2u);
}

TEST_F(HttpServerControl, AControlApiWithoutATokenIsRefusedAtConstruction) {
  HttpRoutes routes;
  routes.control = actions;
  routes.stream_hub = [&]() -> SubscriberHub& { return hub; };
  EXPECT_THROW(HttpServer(io_thread.io, "127.0.0.1", 0, std::move(routes)), std::invalid_argument);
}

// skinstream-ctl, the real program, beside this test's program in the build's bin/.
std::string ctl_program() {
  return (std::filesystem::read_symlink("/proc/self/exe").parent_path() / "skinstream-ctl").string();
}

struct ProgramRun {
  int exit_code = -1;
  std::string out, err;
};

// Runs skinstream-ctl with `arguments` (shell words) and SKINSTREAM_CONTROL_TOKEN unset.
ProgramRun run_ctl(const std::string& arguments) {
  const std::string out = test::scratch_path("ctl.out"), err = test::scratch_path("ctl.err");
  const std::string command =
      "env -u SKINSTREAM_CONTROL_TOKEN " + ctl_program() + " " + arguments + " > " + out + " 2> " + err;
  const int status = std::system(command.c_str());
  auto read = [](const std::string& path) {
    std::ifstream in(path);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, read(out), read(err)};
}

TEST_F(HttpServerControl, SkinstreamCtlStartsStopsAndListsTakesAndExitsOneOnRefusals) {
  ASSERT_TRUE(std::filesystem::exists(ctl_program())) << ctl_program() << ": build skinstream-ctl";
  start(true);
  const std::string token_file = test::scratch_path("ctl-token");
  std::ofstream(token_file) << kControlToken << "\n";
  const std::string common =
      "--port " + std::to_string(port) + " --token-file " + token_file + " --operator anna";

  const ProgramRun started = run_ctl(common + " take start 'take 7'");
  EXPECT_EQ(started.exit_code, 0) << started.err;
  EXPECT_EQ(nlohmann::json::parse(started.out).at("take"), "take 7");
  const ProgramRun stopped = run_ctl(common + " take stop");
  EXPECT_EQ(stopped.exit_code, 1);  // the double answers 409
  EXPECT_NE(stopped.err.find("409 no take is being recorded"), std::string::npos) << stopped.err;
  const ProgramRun listed = run_ctl(common + " takes");
  EXPECT_EQ(listed.exit_code, 0) << listed.err;
  EXPECT_EQ(nlohmann::json::parse(listed.out).at("takes").size(), 2u);

  const std::vector<RecordingControlActions::Call> calls = actions->calls();
  ASSERT_EQ(calls.size(), 3u);
  EXPECT_EQ(calls[0].action, "start_take");
  EXPECT_EQ(calls[0].caller.operator_name, "anna");
  EXPECT_EQ(calls[0].request.at("name"), "take 7");
  EXPECT_EQ(calls[1].action, "stop_take");

  const std::string wrong_file = test::scratch_path("ctl-wrong-token");
  std::ofstream(wrong_file) << "not-the-token-0123456789\n";
  const ProgramRun refused =
      run_ctl("--port " + std::to_string(port) + " --token-file " + wrong_file + " takes");
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_NE(refused.err.find("403 wrong token"), std::string::npos) << refused.err;
  EXPECT_EQ(refused.err.find('\n'), refused.err.size() - 1) << "one line: " << refused.err;
  EXPECT_EQ(actions->calls().size(), 3u);
  EXPECT_EQ(run_ctl("--port " + std::to_string(port) + " take").exit_code, 2);
}

}  // namespace
}  // namespace skinstream::server
