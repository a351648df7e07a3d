#pragma once
// The real skinstreamd in the background, as a user starts it, on ephemeral loopback ports (read
// back from its ports file); stopped with SIGTERM. `arguments` go on its command line as given;
// `shell_prefix` runs before it in the same shell (e.g. "ulimit -n 64; ").
#include <string>
#include <sys/types.h>

namespace skinstream::test {

class DaemonProcess {
 public:
  // Waits until the daemon listens; a daemon that exits at startup fails the test (ADD_FAILURE)
  // with its log, and leaves the ports at 0.
  DaemonProcess(const std::string& skinstreamd, const std::string& arguments, const std::string& shell_prefix = "");
  ~DaemonProcess();
  DaemonProcess(const DaemonProcess&) = delete;
  DaemonProcess& operator=(const DaemonProcess&) = delete;

  int stop();  // its exit code (-1: killed by a signal)
  std::string log() const;
  pid_t pid() const { return pid_; }  // the daemon's own (the shell execs it)
  int http_port = 0, sub_port = 0;

 private:
  pid_t pid_ = -1;
  int exit_code_ = -1;
  std::string ports_path_, log_path_;
};

}  // namespace skinstream::test
