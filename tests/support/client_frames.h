#pragma once
// Frames from one subscriber of the C++ client library, by frame number, until it has `count` of
// them or two minutes have passed: `keep(frame, kept)` takes what a test compares of each.
#include <chrono>
#include <cstdint>
#include <map>

#include "skinstream/client.h"

namespace skinstream::test {

template <typename Kept, typename Keep>
std::map<uint32_t, Kept> receive_frames(client::Subscriber& sub, int count, Keep keep) {
  std::map<uint32_t, Kept> frames;
  client::Frame frame;
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (static_cast<int>(frames.size()) < count && std::chrono::steady_clock::now() < give_up) {
    if (!sub.next(frame, std::chrono::seconds(1))) continue;
    keep(frame, frames[frame.frame_number]);
  }
  return frames;
}

}  // namespace skinstream::test
