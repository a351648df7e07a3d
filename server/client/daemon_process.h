#pragma once
// The real skinstreamd as a child process, started as a user starts it, for the benchmark and the
// end-to-end tests: ephemeral ports (read back from its ports file), its output in a log file,
// stopped with SIGTERM. One harness, so the bench and the tests start it the same way.
#include <chrono>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <sys/types.h>

namespace skinstream::server {

struct DaemonLaunch {
  std::string program;            // the skinstreamd to run
  std::string arguments;          // its command line after the listening options, as shell words
  std::string shell_prefix;       // run first in the same shell, e.g. "ulimit -n 64; "
  std::string exec_prefix;        // words before the program, e.g. "ip netns exec NAME"
  std::string bind = "127.0.0.1";  // --bind, and where health() asks
  std::string files_stem;          // the ports file is files_stem.ports.json, the log files_stem.log
  std::chrono::milliseconds startup_timeout{30000};
};

// Quotes a word for /bin/sh (single quotes; a quote inside becomes '\'').
std::string shell_word(const std::string& word);

class DaemonProcess {
 public:
  // Starts it and waits until it listens. Throws std::runtime_error, with the daemon's log, when
  // it exits first or does not listen within the timeout (and then stops it).
  explicit DaemonProcess(DaemonLaunch launch);
  ~DaemonProcess();
  DaemonProcess(const DaemonProcess&) = delete;
  DaemonProcess& operator=(const DaemonProcess&) = delete;

  int http_port() const { return http_port_; }
  int sub_port() const { return sub_port_; }
  const std::string& address() const { return launch_.bind; }
  pid_t pid() const { return pid_; }  // the daemon's own: the shell execs it
  bool running();                     // false once it has exited (reaped here)
  std::string log() const;
  const std::string log_path() const { return launch_.files_stem + ".log"; }

  nlohmann::json health() const;
  // Until /health says the source streams; throws with the log when it exits or times out.
  void wait_until_streaming(std::chrono::milliseconds timeout);
  // SIGTERM and wait: its exit code (-1 when a signal ended it). Idempotent.
  int stop();

 private:
  DaemonLaunch launch_;
  pid_t pid_ = -1;
  int exit_code_ = -1;
  int http_port_ = 0, sub_port_ = 0;
};

}  // namespace skinstream::server
