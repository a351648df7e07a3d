#pragma once
// The network programs in the background, for end-to-end tests on loopback: skinstreamd
// (support/daemon_process.h) and skinstream-replay as child processes (the paths come from the
// test target's SKINSTREAMD and SKINSTREAM_REPLAY), a subscriber on its own thread, and polling
// with a bound.
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <functional>
#include <mutex>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "support/subscriber_client.h"
#include "support/daemon_process.h"
#include "support/loopback_peer.h"  // eventually()
#include "support/test_data.h"

namespace skinstream::test {

// skinstream-replay in the background: a Vicon DataStream server looping a recording (or
// several: `recording` goes on the command line as it is).
class ReplayProcess {
 public:
  // port 0: any free port (see port). `extra` goes on the command line as it is; `shell_prefix`
  // runs before it in the same shell (e.g. "ulimit -n 32; ").
  ReplayProcess(const std::string& recording, int port, const std::string& extra = "", const std::string& shell_prefix = "") {
    out_path_ = scratch_path("replay_" + std::to_string(getpid()) + "_" + std::to_string(counter_++) + ".out");
    std::remove(out_path_.c_str());
    pid_ = fork();
    if (pid_ == 0) {
      const std::string command = shell_prefix + "exec " + std::string(SKINSTREAM_REPLAY) + " " + recording + " --bind 127.0.0.1 --port " +
                                  std::to_string(port) + " --loop " + extra + " > " + out_path_ + " 2> " + out_path_ + ".log";
      execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
      _exit(127);
    }
    for (;;) {
      std::ifstream in(out_path_);
      std::string line;
      if (in && std::getline(in, line) && line.find('}') != std::string::npos) {
        this->port = nlohmann::json::parse(line)["port"];
        return;
      }
      if (waitpid(pid_, nullptr, WNOHANG) == pid_) {
        pid_ = -1;
        ADD_FAILURE() << "skinstream-replay exited at startup";
        return;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }
  ~ReplayProcess() { kill_now(); }
  // SIGKILL: the source vanishes as a crashed or unplugged server would, without a goodbye.
  void kill_now() {
    if (pid_ <= 0) return;
    kill(pid_, SIGKILL);
    waitpid(pid_, nullptr, 0);
    pid_ = -1;
  }
  pid_t pid() const { return pid_; }
  std::string log() const {
    std::ifstream in(out_path_ + ".log");
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  }
  int port = 0;

 private:
  static inline int counter_ = 0;
  pid_t pid_ = -1;
  std::string out_path_;
};

// A subscriber on its own thread that keeps every Status and counts frames, until stopped.
class BackgroundSubscriber {
 public:
  BackgroundSubscriber(int port, uint32_t wants) {
    thread_ = std::thread([this, port, wants] {
      try {
        sub::SubscriberClient client("127.0.0.1", std::to_string(port), wants);
        client.run([this](subscriber::MessageType type, std::span<const unsigned char> payload, int64_t) {
          std::lock_guard lock(mutex_);
          if (type == subscriber::MessageType::Status) statuses_.push_back(subscriber::decode_status(payload));
          if (type == subscriber::MessageType::Frame) {
            last_frame_number_ = subscriber::decode_frame(payload).info.frame_number;
            ++frames_;
          }
          return !stop_.load();
        });
      } catch (const std::exception& e) {
        std::lock_guard lock(mutex_);
        error_ = e.what();
      }
      closed_ = true;
    });
  }
  ~BackgroundSubscriber() {
    stop_ = true;
    thread_.join();  // a Status arrives at least every status interval, so run() returns
  }
  long frames() const {
    std::lock_guard lock(mutex_);
    return frames_;
  }
  uint32_t last_frame_number() const {
    std::lock_guard lock(mutex_);
    return last_frame_number_;
  }
  // Statuses received from index `from` on with this state.
  bool saw_status(subscriber::SourceStateCode state, size_t from = 0) const {
    std::lock_guard lock(mutex_);
    for (size_t i = from; i < statuses_.size(); ++i)
      if (statuses_[i].state == state) return true;
    return false;
  }
  size_t status_count() const {
    std::lock_guard lock(mutex_);
    return statuses_.size();
  }
  std::string last_status_detail() const {
    std::lock_guard lock(mutex_);
    return statuses_.empty() ? std::string() : statuses_.back().detail;
  }
  bool closed() const { return closed_.load(); }
  std::string error() const {
    std::lock_guard lock(mutex_);
    return error_;
  }

 private:
  mutable std::mutex mutex_;
  std::vector<subscriber::Status> statuses_;
  long frames_ = 0;
  uint32_t last_frame_number_ = 0;
  std::string error_;
  std::atomic<bool> stop_{false}, closed_{false};
  std::thread thread_;
};

// A port free on loopback right now (type SOCK_STREAM or SOCK_DGRAM): bound, noted, closed.
inline int free_loopback_port(int type) {
  const int holder = socket(AF_INET, type, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (bind(holder, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0) {
    close(holder);
    return 0;
  }
  socklen_t length = sizeof address;
  getsockname(holder, reinterpret_cast<sockaddr*>(&address), &length);
  close(holder);
  return ntohs(address.sin_port);
}

}  // namespace skinstream::test
