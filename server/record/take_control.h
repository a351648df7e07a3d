#pragma once
// The control API's take routes (docs/control-api.md) answered by the take recorder: POST /takes,
// POST /takes/stop, GET /takes (DaemonControl calls them). Without a record_dir there is no recorder:
// starting a take is refused with the reason (409), and the list is empty.

#include "server/control/control_actions.h"
#include "server/record/take_recorder.h"

namespace skinstream::server {

class TakeControl {
 public:
  explicit TakeControl(TakeRecorder* recorder) : recorder_(recorder) {}

  ControlAnswer start_take(const ControlCaller& caller, const nlohmann::json& request);
  ControlAnswer stop_take(const ControlCaller& caller);
  ControlAnswer list_takes();

  // "control from 10.0.0.5 (anna)": who a take's take.json and the log say started it.
  static std::string who(const ControlCaller& caller);

 private:
  TakeRecorder* recorder_;  // null: recording is off
};

}  // namespace skinstream::server
