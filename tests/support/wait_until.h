#pragma once
// Waits for a condition the code under test must reach soon; a test stuck here fails after a
// minute instead of hanging (a bound on a hang, not a timing assertion).
#include <gtest/gtest.h>

#include <chrono>
#include <functional>
#include <thread>

namespace skinstream::test {

inline void wait_until(const std::function<bool()>& done) {
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (!done()) {
    if (std::chrono::steady_clock::now() > give_up) {
      ADD_FAILURE() << "condition not reached within 60 s";
      return;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

}  // namespace skinstream::test
