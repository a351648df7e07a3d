#include "support/daemon_process.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>

#include "support/test_data.h"

namespace skinstream::test {

DaemonProcess::DaemonProcess(const std::string& arguments, const std::string& shell_prefix) {
  static std::atomic<int> counter{0};
  server::DaemonLaunch launch;
  launch.program = SKINSTREAMD;
  launch.arguments = arguments;
  launch.shell_prefix = shell_prefix;
  // The process id too: ctest runs each test as its own process, several at once.
  launch.files_stem = scratch_path("daemon_" + std::to_string(getpid()) + "_" + std::to_string(counter++));
  try {
    process_ = std::make_unique<server::DaemonProcess>(launch);
    http_port = process_->http_port();
    sub_port = process_->sub_port();
  } catch (const std::exception& e) {
    startup_error_ = e.what();
    ADD_FAILURE() << e.what();
  }
}

DaemonProcess::~DaemonProcess() = default;

int DaemonProcess::stop() { return process_ ? process_->stop() : -1; }
std::string DaemonProcess::log() const { return process_ ? process_->log() : startup_error_; }
pid_t DaemonProcess::pid() const { return process_ ? process_->pid() : -1; }

}  // namespace skinstream::test
