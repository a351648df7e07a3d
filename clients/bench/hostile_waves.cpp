#include "clients/bench/hostile_waves.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <deque>
#include <string>
#include <vector>

#include "protocol/subscriber/subscriber_stream.h"

namespace skinstream::bench {
namespace {

// A connection to 127.0.0.1:port from 127.0.0.(2 + n % 8), or -1.
int connect_from_host(int port, int n, int receive_buffer_bytes = 0) {
  const int fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return -1;
  if (receive_buffer_bytes > 0) setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &receive_buffer_bytes, sizeof receive_buffer_bytes);
  sockaddr_in local{};
  local.sin_family = AF_INET;
  local.sin_addr.s_addr = htonl(INADDR_LOOPBACK + 2 + static_cast<uint32_t>(n % 8));
  sockaddr_in remote{};
  remote.sin_family = AF_INET;
  remote.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  remote.sin_port = htons(static_cast<uint16_t>(port));
  if (bind(fd, reinterpret_cast<sockaddr*>(&local), sizeof local) != 0 ||
      connect(fd, reinterpret_cast<sockaddr*>(&remote), sizeof remote) != 0) {
    close(fd);
    return -1;
  }
  return fd;
}

// Sends without waiting; false when the daemon closed the connection.
bool send_now(int fd, const void* data, size_t size) {
  const ssize_t n = send(fd, data, size, MSG_DONTWAIT | MSG_NOSIGNAL);
  return n >= 0 || errno == EAGAIN || errno == EWOULDBLOCK;
}

std::vector<unsigned char> hello_bytes(uint32_t wants) { return subscriber::encode_hello(subscriber::Hello{wants}); }

void close_all(std::vector<int>& fds) {
  for (int fd : fds)
    if (fd >= 0) close(fd);
  fds.clear();
}

}  // namespace

HostileWaves::HostileWaves(HostileWaveOptions options, std::function<long()> rss_kb)
    : options_(options), rss_kb_(std::move(rss_kb)) {}

HostileWaves::~HostileWaves() { stop(); }

void HostileWaves::start() {
  start_ = std::chrono::steady_clock::now();
  thread_ = std::thread([this] { run(); });
}

void HostileWaves::stop() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
}

nlohmann::json HostileWaves::report() const {
  std::lock_guard lock(mutex_);
  return {{"waves", waves_},
          {"per_wave",
           {{"seconds", options_.wave.count()},
            {"calm_seconds", options_.calm.count()},
            {"stallers", options_.peers.stallers},
            {"websocket_stallers", options_.peers.websocket_stallers},
            {"garbage_flooders", options_.peers.garbage_flooders},
            {"hello_flooders", options_.peers.hello_flooders},
            {"churn_per_second", options_.peers.churn_per_second}}}};
}

bool HostileWaves::sleep_unless_stopped(std::chrono::milliseconds duration) {
  const auto end = std::chrono::steady_clock::now() + duration;
  while (!stop_.load() && std::chrono::steady_clock::now() < end) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  return !stop_.load();
}

void HostileWaves::run() {
  while (!stop_.load()) {
    nlohmann::json entry = {{"started_s", std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count()},
                            {"rss_kb_before", rss_kb_()}};
    wave(entry);
    if (!sleep_unless_stopped(options_.calm)) break;
    entry["rss_kb_after_calm"] = rss_kb_();
    std::lock_guard lock(mutex_);
    waves_.push_back(entry);
  }
}

void HostileWaves::wave(nlohmann::json& out) {
  long connections = 0, peak = 0;
  std::vector<int> stallers, websockets, garbage, hellos;
  std::deque<int> churn;
  const std::vector<unsigned char> positions = hello_bytes(0);
  for (int i = 0; i < options_.peers.stallers; ++i) {
    const int fd = connect_from_host(options_.sub_port, i, 4096);
    if (fd >= 0 && send_now(fd, positions.data(), positions.size())) ++connections;
    stallers.push_back(fd);
  }
  const std::string upgrade =
      "GET /stream HTTP/1.1\r\nHost: 127.0.0.1\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
      "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n";
  for (int i = 0; i < options_.peers.websocket_stallers; ++i) {
    const int fd = connect_from_host(options_.http_port, i, 4096);
    if (fd >= 0 && send_now(fd, upgrade.data(), upgrade.size())) ++connections;
    websockets.push_back(fd);
  }
  garbage.assign(static_cast<size_t>(options_.peers.garbage_flooders), -1);
  hellos.assign(static_cast<size_t>(options_.peers.hello_flooders), -1);
  std::vector<unsigned char> noise(16384);
  for (size_t i = 0; i < noise.size(); ++i) noise[i] = static_cast<unsigned char>(i * 131 + 7);
  const auto end = std::chrono::steady_clock::now() + options_.wave;
  const auto tick = std::chrono::milliseconds(50);
  // Rounded up to one a tick unless no churn is asked for.
  const int churn_per_tick = options_.peers.churn_per_second > 0 ? std::max(1, options_.peers.churn_per_second / 20) : 0;
  uint32_t wants = 0;
  for (int n = 0; !stop_.load() && std::chrono::steady_clock::now() < end; ++n) {
    for (size_t i = 0; i < garbage.size(); ++i) {
      if (garbage[i] < 0) {
        garbage[i] = connect_from_host(options_.sub_port, static_cast<int>(i));
        connections += garbage[i] >= 0;
      }
      if (garbage[i] >= 0 && !send_now(garbage[i], noise.data(), noise.size())) {
        close(garbage[i]);
        garbage[i] = -1;
      }
    }
    // Every valid wants in turn: each Hello asks for something else.
    wants = (wants + 1) % 32;
    const std::vector<unsigned char> hello = hello_bytes(wants & ~subscriber::kWantPaced);
    for (size_t i = 0; i < hellos.size(); ++i) {
      if (hellos[i] < 0) {
        hellos[i] = connect_from_host(options_.sub_port, static_cast<int>(i), 4096);
        connections += hellos[i] >= 0;
      }
      if (hellos[i] >= 0 && !send_now(hellos[i], hello.data(), hello.size())) {
        close(hellos[i]);
        hellos[i] = -1;
      }
    }
    for (int c = 0; c < churn_per_tick; ++c) {
      const int fd = connect_from_host(options_.sub_port, n + c);
      if (fd < 0) continue;
      ++connections;
      send_now(fd, positions.data(), positions.size());
      churn.push_back(fd);
    }
    while (churn.size() > static_cast<size_t>(churn_per_tick * 4)) {
      close(churn.front());
      churn.pop_front();
    }
    if (n % 20 == 0) peak = std::max(peak, rss_kb_());
    std::this_thread::sleep_for(tick);
  }
  close_all(stallers);
  close_all(websockets);
  close_all(garbage);
  close_all(hellos);
  for (int fd : churn) close(fd);
  out["rss_kb_peak"] = peak;
  out["connections"] = connections;
}

}  // namespace skinstream::bench
