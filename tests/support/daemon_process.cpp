#include "support/daemon_process.h"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "support/test_data.h"

namespace skinstream::test {

DaemonProcess::DaemonProcess(const std::string& skinstreamd, const std::string& arguments, const std::string& shell_prefix) {
  static std::atomic<int> counter{0};
  // The process id too: ctest runs each test as its own process, several at once.
  ports_path_ = scratch_path("ports_" + std::to_string(getpid()) + "_" + std::to_string(counter++) + ".json");
  std::remove(ports_path_.c_str());
  log_path_ = ports_path_ + ".log";
  pid_ = fork();
  if (pid_ == 0) {
    const std::string command = shell_prefix + "exec " + skinstreamd + " --bind 127.0.0.1 --http-port 0 --sub-port 0 --ports-file " + ports_path_ + " " +
                                arguments + " > " + log_path_ + " 2>&1";
    execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  for (;;) {
    std::ifstream in(ports_path_);
    if (in) {
      const nlohmann::json ports = nlohmann::json::parse(in);
      http_port = ports["http"];
      sub_port = ports["sub"];
      return;
    }
    int status = 0;
    if (waitpid(pid_, &status, WNOHANG) == pid_) {
      pid_ = -1;
      ADD_FAILURE() << "skinstreamd exited at startup: " << log();
      return;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

DaemonProcess::~DaemonProcess() { stop(); }

int DaemonProcess::stop() {
  if (pid_ <= 0) return exit_code_;
  kill(pid_, SIGTERM);
  int status = 0;
  waitpid(pid_, &status, 0);
  pid_ = -1;
  exit_code_ = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return exit_code_;
}

std::string DaemonProcess::log() const {
  std::ifstream in(log_path_);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace skinstream::test
