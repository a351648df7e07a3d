#include "server/record/take_control.h"

namespace skinstream::server {
namespace {

ControlAnswer recording_off() {
  return {409, {{"error", "recording is off: the daemon has no record_dir (--record-dir)"}}};
}

}  // namespace

std::string TakeControl::who(const ControlCaller& caller) {
  std::string who = "control from " + caller.address;
  if (!caller.operator_name.empty()) who += " (" + caller.operator_name + ")";
  return who;
}

ControlAnswer TakeControl::start_take(const ControlCaller& caller, const nlohmann::json& request) {
  if (!recorder_) return recording_off();
  std::string name;
  if (request.is_object() && request.contains("name")) {
    if (!request["name"].is_string()) return {400, {{"error", "\"name\" must be a string"}}};
    name = request["name"].get<std::string>();
  }
  const TakeAnswer answer = recorder_->start(name, who(caller));
  return {answer.status, answer.body};
}

ControlAnswer TakeControl::stop_take(const ControlCaller& caller) {
  if (!recorder_) return recording_off();
  const TakeAnswer answer = recorder_->stop(who(caller));
  return {answer.status, answer.body};
}

ControlAnswer TakeControl::list_takes() {
  if (!recorder_) return {200, {{"folder", ""}, {"takes", nlohmann::json::array()}}};
  return {200, recorder_->list()};
}

}  // namespace skinstream::server
