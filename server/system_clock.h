#pragma once
// The wall clock as nanoseconds since the Unix epoch: the time stamps that leave the process
// (a frame's receive and send times, which subscribers on other hosts compare with their own).
#include <chrono>
#include <cstdint>

namespace skinstream::server {

inline int64_t system_now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
}

}  // namespace skinstream::server
