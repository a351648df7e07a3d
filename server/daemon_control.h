#pragma once
// The control API's actions (server/control/control_actions.h) as the daemon answers them: the
// takes by the take recorder (TakeControl), the subjects by SubjectChanges.

#include "server/control/control_actions.h"
#include "server/record/take_control.h"
#include "server/subjects/subject_changes.h"

namespace skinstream::server {

class DaemonControl final : public ControlActions {
 public:
  DaemonControl(TakeRecorder* recorder, SubjectChanges& subjects) : takes_(recorder), subjects_(subjects) {}

  ControlAnswer start_take(const ControlCaller& caller, const nlohmann::json& request) override {
    return takes_.start_take(caller, request);
  }
  ControlAnswer stop_take(const ControlCaller& caller) override { return takes_.stop_take(caller); }
  ControlAnswer list_takes() override { return takes_.list_takes(); }
  ControlAnswer calibrate_subject(const ControlCaller& caller, const std::string& name,
                                  const nlohmann::json& request) override {
    return subjects_.calibrate(name, request, TakeControl::who(caller));
  }
  ControlAnswer load_subject_file(const ControlCaller& caller, const std::string& name,
                                  const nlohmann::json& request) override {
    return subjects_.load_file(name, request, TakeControl::who(caller));
  }
  ControlAnswer add_subject(const ControlCaller& caller, const nlohmann::json& request) override {
    return subjects_.add(request, TakeControl::who(caller));
  }
  ControlAnswer remove_subject(const ControlCaller& caller, const std::string& name) override {
    return subjects_.remove(name, TakeControl::who(caller));
  }
  ControlAnswer subject_state(const std::string& name) override { return subjects_.state(name); }
  ControlAnswer list_subjects() override { return subjects_.list(); }

 private:
  TakeControl takes_;
  SubjectChanges& subjects_;
};

}  // namespace skinstream::server
