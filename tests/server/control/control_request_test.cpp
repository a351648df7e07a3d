#include "server/control/control_request.h"

#include <gtest/gtest.h>

#include <string>

namespace skinstream::server {
namespace {

const std::string kToken = "stage-token-0123456789";
const std::string kBearer = "Bearer " + kToken;

ControlDecision decide(std::string_view method, std::string_view target,
                       std::string_view authorization = kBearer, std::string_view body = "",
                       std::string_view operator_name = "anna") {
  return decide_control_request({method, target, authorization, operator_name, body}, kToken);
}

void expect_one_printable_line(const std::string& reason) {
  EXPECT_FALSE(reason.empty());
  for (const char c : reason) EXPECT_TRUE(c >= 0x20 && c < 0x7f) << reason;
}

TEST(ControlRequest, UnknownPathsAre404) {
  for (const char* target : {"/takes/start", "/takes/stop/now", "/takes//stop", "/subjects/Actor1/other"}) {
    const ControlDecision decision = decide("POST", target);
    EXPECT_EQ(decision.status, 404) << target;
    EXPECT_EQ(decision.route, nullptr);
    expect_one_printable_line(decision.reason);
  }
}

TEST(ControlRequest, AKnownPathWithAnotherMethodIs405WithTheMethodsItTakes) {
  const ControlDecision stop = decide("GET", "/takes/stop");
  EXPECT_EQ(stop.status, 405);
  EXPECT_EQ(stop.allow, "POST");
  const ControlDecision takes = decide("DELETE", "/takes");
  EXPECT_EQ(takes.status, 405);
  EXPECT_EQ(takes.allow, "GET, POST");
  expect_one_printable_line(takes.reason);
}

TEST(ControlRequest, RoutesAreFoundByMethodAndPathWithTheQueryIgnored) {
  const ControlDecision list = decide("GET", "/takes?verbose=1");
  ASSERT_EQ(list.status, 200) << list.reason;
  EXPECT_EQ(list.route->action, ControlAction::ListTakes);
  EXPECT_EQ(decide("POST", "/takes").route->action, ControlAction::StartTake);
  EXPECT_EQ(decide("POST", "/takes/stop").route->action, ControlAction::StopTake);
}

TEST(ControlRequest, NoTokenIs401AndAWrongOneIs403WithoutTheTokenInTheReason) {
  for (const char* authorization :
       {"", "Bearer", "Bearer ", "Basic dXNlcjpwYXNz", "Bearer\tx", kToken.c_str()}) {
    const ControlDecision decision = decide("POST", "/takes/stop", authorization);
    EXPECT_EQ(decision.status, 401) << authorization;
    EXPECT_EQ(decision.route, nullptr);
  }
  for (const std::string& wrong : {kToken + "x", kToken.substr(1), std::string("stage-token-0123456780"),
                                   std::string("Bearer ") + "Bearer " + kToken}) {
    const std::string authorization = wrong.rfind("Bearer ", 0) == 0 ? wrong : "Bearer " + wrong;
    const ControlDecision decision = decide("POST", "/takes/stop", authorization);
    EXPECT_EQ(decision.status, 403) << authorization;
    EXPECT_EQ(decision.reason.find(kToken), std::string::npos);
    EXPECT_EQ(decision.reason.find("stage-token"), std::string::npos);
  }
}

TEST(ControlRequest, TheSchemeIsReadInAnyCaseAndSpacesAroundTheTokenIgnored) {
  EXPECT_EQ(decide("GET", "/takes", "bearer " + kToken).status, 200);
  EXPECT_EQ(decide("GET", "/takes", "BEARER   " + kToken + "  ").status, 200);
  EXPECT_EQ(bearer_token("Bearer abc"), "abc");
  EXPECT_EQ(bearer_token("Bearerabc"), "");
}

TEST(ControlRequest, AnEmptyConfiguredTokenMatchesNothing) {
  EXPECT_EQ(decide_control_request({"GET", "/takes", "Bearer x", "", ""}, "").status, 403);
}

TEST(ControlRequest, TheTokenIsCheckedBeforeTheBody) {
  // Without the token a peer learns nothing of how its body would be read.
  EXPECT_EQ(decide("POST", "/takes", "", "{not json").status, 401);
  EXPECT_EQ(decide("POST", "/takes", "Bearer wrong-token-000000", std::string(20'000, ' ')).status, 403);
}

TEST(ControlRequest, BodiesOverTheLimitAre413) {
  const std::string padding(kMaxControlBodyBytes - 11, ' ');
  const std::string at_limit = "{\"name\":1}" + padding + " ";
  ASSERT_EQ(at_limit.size(), kMaxControlBodyBytes);
  EXPECT_EQ(decide("POST", "/takes", kBearer, at_limit).status, 200);
  const ControlDecision over = decide("POST", "/takes", kBearer, at_limit + " ");
  EXPECT_EQ(over.status, 413);
  expect_one_printable_line(over.reason);
}

TEST(ControlRequest, BadJsonIs400WithOneLine) {
  for (const char* body :
       {"{", "{\"name\": }", "name=take1", "{\"name\": \"a\"} trailing", "{\"a\":\"\xff\"}"}) {
    const ControlDecision decision = decide("POST", "/takes", kBearer, body);
    EXPECT_EQ(decision.status, 400) << body;
    expect_one_printable_line(decision.reason);
  }
}

TEST(ControlRequest, ANumberBeyondADoubleIs400NotAnException) {
  // Found by the fuzz target (tests/fuzz/seeds/control_request/number_out_of_range.txt).
  const ControlDecision decision = decide("POST", "/takes", kBearer, "12.4567801234e339");
  EXPECT_EQ(decision.status, 400);
  EXPECT_EQ(decide("POST", "/takes", kBearer, R"({"name": 1e400})").status, 400);
  expect_one_printable_line(decision.reason);
}

TEST(ControlRequest, ABodyMustBeAJsonObject) {
  for (const char* body : {"[]", "\"take1\"", "3", "null", "true"}) {
    const ControlDecision decision = decide("POST", "/takes", kBearer, body);
    EXPECT_EQ(decision.status, 400) << body;
    EXPECT_NE(decision.reason.find("object"), std::string::npos) << decision.reason;
  }
}

TEST(ControlRequest, DeepNestingIsRefused) {
  std::string deep = "{\"a\":";
  for (int i = 0; i < 100; ++i) deep += "[";
  for (int i = 0; i < 100; ++i) deep += "]";
  deep += "}";
  EXPECT_EQ(decide("POST", "/takes", kBearer, deep).status, 400);
}

TEST(ControlRequest, TheBodyIsHandedOverAndNoneIsAnEmptyObject) {
  const ControlDecision named = decide("POST", "/takes", kBearer, R"({"name": "take 7"})");
  ASSERT_EQ(named.status, 200) << named.reason;
  EXPECT_EQ(named.body.at("name"), "take 7");
  const ControlDecision unnamed = decide("POST", "/takes", kBearer, " \r\n");
  ASSERT_EQ(unnamed.status, 200);
  EXPECT_TRUE(unnamed.body.is_object());
  EXPECT_TRUE(unnamed.body.empty());
}

TEST(ControlRequest, RoutesWithoutABodyRefuseOne) {
  EXPECT_EQ(decide("POST", "/takes/stop", kBearer, "{}").status, 400);
  EXPECT_EQ(decide("POST", "/takes/stop", kBearer, "").status, 200);
}

TEST(ControlRequest, TheOperatorNameIsPrintableAndBounded) {
  EXPECT_EQ(decide("GET", "/takes", kBearer, "", std::string(kMaxControlOperatorBytes, 'a')).status, 200);
  EXPECT_EQ(decide("GET", "/takes", kBearer, "", std::string(kMaxControlOperatorBytes + 1, 'a')).status, 400);
  EXPECT_EQ(decide("GET", "/takes", kBearer, "", "anna\x1b[2J").status, 400);
  EXPECT_EQ(decide("GET", "/takes", kBearer, "", "").status, 200);
}

}  // namespace
}  // namespace skinstream::server
