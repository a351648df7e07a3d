#pragma once
// The real skinstreamd in the background for a test, through the harness the bench uses too
// (server/client/daemon_process.h), on ephemeral loopback ports. A daemon that exits at startup
// fails the test (ADD_FAILURE, with its log) and leaves the ports at 0. The program is the test
// target's SKINSTREAMD.
#include <memory>
#include <string>
#include <sys/types.h>

#include "server/client/daemon_process.h"

namespace skinstream::test {

class DaemonProcess {
 public:
  // `arguments` go on its command line as shell words; `shell_prefix` runs first in the same
  // shell (e.g. "ulimit -n 64; ").
  explicit DaemonProcess(const std::string& arguments, const std::string& shell_prefix = "");
  ~DaemonProcess();
  DaemonProcess(const DaemonProcess&) = delete;
  DaemonProcess& operator=(const DaemonProcess&) = delete;

  int stop();  // its exit code (-1: killed by a signal, or it never started)
  std::string log() const;
  pid_t pid() const;
  int http_port = 0, sub_port = 0;

 private:
  std::unique_ptr<server::DaemonProcess> process_;
  std::string startup_error_;
};

}  // namespace skinstream::test
