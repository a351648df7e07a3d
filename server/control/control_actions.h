#pragma once
// What the operator's control API (docs/control-api.md) asks the daemon to do. The daemon
// implements it; the HTTP server calls it once a request's route, token and body are right
// (server/control/control_request.h), so an implementation sees only authorized requests.

#include <nlohmann/json.hpp>
#include <string>

namespace skinstream::server {

struct ControlCaller {
  std::string address;        // the peer's address
  std::string operator_name;  // its X-Skinstream-Operator header (printable, bounded) or empty
};

struct ControlAnswer {
  int status = 200;
  nlohmann::json body;  // sent as JSON
};

class ControlActions {
 public:
  virtual ~ControlActions() = default;
  // Called on the HTTP io thread: must answer quickly (may open a file, never waits for a frame).
  virtual ControlAnswer start_take(const ControlCaller& caller,
                                   const nlohmann::json& request) = 0;  // POST /takes
  virtual ControlAnswer stop_take(const ControlCaller& caller) = 0;     // POST /takes/stop
  virtual ControlAnswer list_takes() = 0;                               // GET /takes
  // POST /subjects/NAME/calibration: record the subject's range of motion, build, check, swap in.
  virtual ControlAnswer calibrate_subject(const ControlCaller& caller, const std::string& name,
                                          const nlohmann::json& request) = 0;
  // POST /subjects/NAME/file: another subject file for subject NAME, checked, swapped in.
  virtual ControlAnswer load_subject_file(const ControlCaller& caller, const std::string& name,
                                          const nlohmann::json& request) = 0;
  // POST /subjects {"name", "file"}: another subject served from now on.
  virtual ControlAnswer add_subject(const ControlCaller& caller, const nlohmann::json& request) = 0;
  // DELETE /subjects/NAME: subject NAME no longer served; its subscribers told and closed.
  virtual ControlAnswer remove_subject(const ControlCaller& caller, const std::string& name) = 0;
  virtual ControlAnswer subject_state(const std::string& name) = 0;  // GET /subjects/NAME
  virtual ControlAnswer list_subjects() = 0;                         // GET /subjects
};

}  // namespace skinstream::server
