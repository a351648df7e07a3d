#pragma once
// A wait on a condition that no event announces (a server's counter, a file appearing): bounds a
// hang without timing anything.
#include <chrono>
#include <functional>
#include <thread>

namespace skinstream::test {

// Polls `condition` every 20 ms for up to `limit`; true as soon as it holds.
inline bool eventually(const std::function<bool()>& condition, std::chrono::seconds limit = std::chrono::seconds(20)) {
  const auto end = std::chrono::steady_clock::now() + limit;
  while (std::chrono::steady_clock::now() < end) {
    if (condition()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return condition();
}

}  // namespace skinstream::test
