#pragma once
// Calls the action of a decided control request (control_request.h) on the daemon's
// ControlActions: one case per ControlAction.

#include "server/control/control_actions.h"
#include "server/control/control_request.h"

namespace skinstream::server {

// `decision` must be accepted (status 200, a route).
ControlAnswer run_control_action(ControlActions& actions, const ControlDecision& decision,
                                 const ControlCaller& caller);

}  // namespace skinstream::server
