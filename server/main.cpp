// skinstreamd: the streaming daemon. Live (or replayed) marker frames in; gap-filled markers and
// the deformed skin mesh out to every subscriber (TCP and WebSocket), with /health and /metrics.
// Errors at startup print one line and exit 1; SIGINT/SIGTERM stop cleanly with exit code 0.
#include <spdlog/spdlog.h>

#include <malloc.h>

#include <csignal>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "server/config.h"
#include "server/config_keys.h"
#include "server/daemon.h"
#include "server/logging.h"

int main(int argc, char** argv) {
  using namespace skinstream::server;
  // Large buffers (pooled frames of 320 kB-1.3 MB, the MeshInfo of 1.35 MB: few, long-lived)
  // each in a mapping of their own, returned to the system the moment they are freed.
  // By default malloc raises this threshold to the size of each mapped block it frees, after
  // which such buffers land in its arenas, and what a wave of stalled subscribers took comes
  // back only as far as the arenas' fragmentation lets it.
  mallopt(M_MMAP_THRESHOLD, 128 * 1024);
  try {
    int exit_code = 0;
    const std::optional<CommandLine> command_line = parse_command_line(argc, argv, exit_code);
    if (!command_line) return exit_code;
    if (command_line->print_config) {
      std::printf("%s\n", printable(command_line->config).dump(2).c_str());
      return 0;
    }
    if (command_line->print_reference_config) {
      std::fputs(reference_config().c_str(), stdout);
      return 0;
    }
    set_log_level(command_line->config.log_level);
    Daemon daemon(command_line->config);
    asio::signal_set signals(daemon.io(), SIGINT, SIGTERM);
    signals.async_wait([&daemon](const boost::system::error_code& ec, int signal) {
      if (ec) return;
      spdlog::info("skinstreamd: signal {}", signal);
      daemon.request_stop();
    });
    daemon.start();
    daemon.wait();
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "skinstreamd: error: %s\n", e.what());
    return 1;
  }
}
