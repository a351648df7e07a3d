#pragma once
// Hostile peers against skinstreamd, in waves, for the soak (skinstream-bench --hostile-waves):
// each wave opens, from 127.0.0.2-9 (several remote hosts to the daemon),
//   stallers            TCP subscribers that say Hello for positions and never read
//                       (a 4 kB receive buffer, so their writes stop at once);
//   websocket_stallers  WebSocket upgrades of /stream that never read;
//   garbage_flooders    connections that send bytes that are no protocol, reconnecting when
//                       closed;
//   hello_flooders      subscribers that send Hello after Hello, each with other wants, and
//                       never read;
//   churners            connect, Hello, and hang up a moment later, again and again;
// keeps them for `wave`, then closes them all and stays away for `calm`. The daemon's RSS is
// noted before each wave, at its peak during it, and at the end of the calm after it.

#include <atomic>
#include <chrono>
#include <functional>
#include <mutex>
#include <thread>

#include <nlohmann/json.hpp>

namespace skinstream::bench {

// How many of each kind a wave opens (skinstream-bench --stallers etc.).
struct HostilePeers {
  int stallers = 40, websocket_stallers = 20, garbage_flooders = 10, hello_flooders = 10;
  int churn_per_second = 20;
};

struct HostileWaveOptions {
  int sub_port = 0, http_port = 0;
  std::chrono::seconds wave{60}, calm{60};
  HostilePeers peers;
};

class HostileWaves {
 public:
  // `rss_kb` reads the daemon's resident set (kB); called from the waves' thread.
  HostileWaves(HostileWaveOptions options, std::function<long()> rss_kb);
  ~HostileWaves();
  void start();
  void stop();  // closes every hostile connection and joins
  // {"waves": [{"started_s", "rss_kb_before", "rss_kb_peak", "rss_kb_after_calm", "connections"}...]}
  nlohmann::json report() const;

 private:
  void run();
  void wave(nlohmann::json& out);
  bool sleep_unless_stopped(std::chrono::milliseconds duration);

  HostileWaveOptions options_;
  std::function<long()> rss_kb_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
  mutable std::mutex mutex_;
  nlohmann::json waves_ = nlohmann::json::array();
  std::chrono::steady_clock::time_point start_;
};

}  // namespace skinstream::bench
