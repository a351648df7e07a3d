#include "server/client/daemon_process.h"

#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <sstream>
#include <thread>

#include "server/client/health_probe.h"

namespace skinstream::server {

std::string shell_word(const std::string& word) {
  std::string quoted = "'";
  for (const char c : word) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

DaemonProcess::DaemonProcess(DaemonLaunch launch) : launch_(std::move(launch)) {
  const std::string ports_path = launch_.files_stem + ".ports.json";
  std::remove(ports_path.c_str());
  const std::string command = launch_.shell_prefix + "exec " + launch_.exec_prefix + " " + shell_word(launch_.program) + " --bind " +
                              shell_word(launch_.bind) + " --http-port 0 --sub-port 0 --ports-file " + shell_word(ports_path) + " " +
                              launch_.arguments + " > " + shell_word(log_path()) + " 2>&1";
  pid_ = fork();
  if (pid_ < 0) throw std::runtime_error("fork failed");
  if (pid_ == 0) {
    // The daemon goes when the process that started it does, even when that one is killed.
    prctl(PR_SET_PDEATHSIG, SIGTERM);
    // Nothing of the starter's (its listening sockets, its subscribers') stays open in the
    // daemon: Asio opens sockets without close-on-exec.
    close_range(3, ~0U, 0);
    execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  const auto deadline = std::chrono::steady_clock::now() + launch_.startup_timeout;
  for (;;) {
    // The daemon writes the file whole and renames it into place: once it opens, it parses.
    if (std::ifstream in(ports_path); in) {
      const nlohmann::json ports = nlohmann::json::parse(in);
      http_port_ = ports.at("http");
      sub_port_ = ports.at("sub");
      return;
    }
    if (!running()) throw std::runtime_error("skinstreamd exited at startup (code " + std::to_string(exit_code_) + "):\n" + log());
    if (std::chrono::steady_clock::now() > deadline) {
      stop();
      throw std::runtime_error("skinstreamd did not listen within " + std::to_string(launch_.startup_timeout.count()) + " ms:\n" + log());
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

DaemonProcess::~DaemonProcess() { stop(); }

bool DaemonProcess::running() {
  if (pid_ <= 0) return false;
  int status = 0;
  if (waitpid(pid_, &status, WNOHANG) != pid_) return true;
  pid_ = -1;
  exit_code_ = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return false;
}

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
  std::ifstream in(log_path());
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

nlohmann::json DaemonProcess::health() const { return fetch_health(launch_.bind, http_port_); }

void DaemonProcess::wait_until_streaming(std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (health()["source"]["state"] != "streaming") {
    if (!running()) throw std::runtime_error("skinstreamd exited:\n" + log());
    if (std::chrono::steady_clock::now() > deadline)
      throw std::runtime_error("skinstreamd's source did not start streaming within " + std::to_string(timeout.count()) + " ms:\n" + log());
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
}

}  // namespace skinstream::server
