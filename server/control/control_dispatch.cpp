#include "server/control/control_dispatch.h"

namespace skinstream::server {

ControlAnswer run_control_action(ControlActions& actions, const ControlDecision& decision,
                                 const ControlCaller& caller) {
  switch (decision.route->action) {
    case ControlAction::StartTake:
      return actions.start_take(caller, decision.body);
    case ControlAction::StopTake:
      return actions.stop_take(caller);
    case ControlAction::ListTakes:
      return actions.list_takes();
    case ControlAction::CalibrateSubject:
      return actions.calibrate_subject(caller, decision.parameters.at(0).second, decision.body);
    case ControlAction::LoadSubjectFile:
      return actions.load_subject_file(caller, decision.parameters.at(0).second, decision.body);
    case ControlAction::AddSubject:
      return actions.add_subject(caller, decision.body);
    case ControlAction::RemoveSubject:
      return actions.remove_subject(caller, decision.parameters.at(0).second);
    case ControlAction::SubjectState:
      return actions.subject_state(decision.parameters.at(0).second);
    case ControlAction::ListSubjects:
      return actions.list_subjects();
  }
  return {500, {{"error", "no action for this route"}}};
}

}  // namespace skinstream::server
