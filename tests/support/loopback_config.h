#pragma once
// A daemon configuration for in-process tests: both ports ephemeral on loopback, a short Hello
// timeout, warnings only. Each test adds its subjects and its source.
#include "server/config.h"

namespace skinstream::test {

inline server::DaemonConfig loopback_config() {
  server::DaemonConfig config;
  config.bind_address = "127.0.0.1";
  config.http_port = 0;
  config.sub_port = 0;
  config.hello_timeout_ms = 200;
  config.log_level = "warn";
  return config;
}

}  // namespace skinstream::test
