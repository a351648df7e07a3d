#pragma once
// "Daemons" written for the clients' tests: a ScriptedDaemon answers a subscriber's Hello with the
// bytes given (and keeps the Hello it got), then keeps the connection open, saying nothing more,
// until the subscriber leaves (or, with Then::Close, closes it a moment later: a daemon whose
// stream ends there). broken_frame_stream() is the stream of one of them whose frames
// include a broken one: MeshInfo (version 2, the parameter encoding, the 3 vertices of the
// protocol's golden Model, tests/protocol/fixtures/subscriber/model.bin), that Model, and `frames`
// parameter Frames numbered 1, 2, ... in the Model's reference pose, the one numbered `broken`
// with an RBF weight that is not finite (what the daemon once published after one absurd
// coordinate from its source).
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <limits>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "protocol/subscriber/subscriber_stream.h"
#include "support/test_data.h"

namespace skinstream::test {

inline std::vector<unsigned char> broken_frame_stream(int frames, int broken) {
  const std::string model = read_bytes(source_path("tests/protocol/fixtures/subscriber/model.bin"));
  subscriber::MeshInfo info;
  info.vertex_count = 3;
  info.part_count = 2;
  info.faces = {{0, 1, 2}};
  info.dominant_part = {0, 0, 1};
  info.subject = "fake";
  info.encoding = subscriber::Encoding::Parameters;
  std::vector<unsigned char> out = subscriber::encode_mesh_info(info, subscriber::kVersion2);
  out.insert(out.end(), model.begin(), model.end());
  // Every part at its reference frame (A = [I 0 0], the Model's R0 and d0: after the 12-byte
  // header, the 16 count bytes and the 36 vertex bytes, 80 bytes a part), the weights 0.
  auto append = [](std::vector<unsigned char>& to, const void* bytes, size_t n) {
    to.insert(to.end(), static_cast<const unsigned char*>(bytes), static_cast<const unsigned char*>(bytes) + n);
  };
  std::vector<unsigned char> block;
  const uint32_t parts = 2, members = 3, flags = 0;
  append(block, &parts, 4);
  append(block, &members, 4);
  for (uint32_t p = 0; p < parts; ++p) {
    float a[27] = {};
    for (int r = 0; r < 3; ++r) a[9 * r + r] = 1.0f;
    append(block, a, sizeof a);
    append(block, model.data() + subscriber::kHeaderBytes + 16 + 36 + 80 * p, 48);
    append(block, &flags, 4);
  }
  const size_t weights_at = block.size();
  block.resize(block.size() + 4 * 3 * members, 0);
  for (int f = 1; f <= frames; ++f) {
    std::vector<unsigned char> frame_block = block;
    if (f == broken) {
      const float infinite = std::numeric_limits<float>::infinity();
      std::memcpy(frame_block.data() + weights_at + 4, &infinite, 4);
    }
    subscriber::FrameInfo frame;
    frame.frame_number = static_cast<uint32_t>(f);
    frame.flags = subscriber::kFrameParameters;
    std::vector<unsigned char> message(subscriber::frame_message_bytes_with_block(frame_block.size(), frame.flags, 0));
    subscriber::encode_frame_with_block(frame, frame_block, {}, {}, message);
    out.insert(out.end(), message.begin(), message.end());
  }
  return out;
}

class ScriptedDaemon {
 public:
  enum class Then { WaitForTheSubscriber, Close };

  explicit ScriptedDaemon(std::vector<unsigned char> reply, Then then = Then::WaitForTheSubscriber)
      : reply_(std::move(reply)) {
    listener_ = socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t length = sizeof address;
    bind(listener_, reinterpret_cast<sockaddr*>(&address), sizeof address);
    listen(listener_, 1);
    getsockname(listener_, reinterpret_cast<sockaddr*>(&address), &length);
    port = ntohs(address.sin_port);
    thread_ = std::thread([this, then] {
      const int peer = accept(listener_, nullptr, nullptr);
      if (peer < 0) return;
      unsigned char buffer[4096];
      const ssize_t n = recv(peer, buffer, sizeof buffer, 0);
      if (n > 0) {
        {
          std::lock_guard lock(mutex_);
          hello_.assign(buffer, buffer + n);
        }
        send(peer, reply_.data(), reply_.size(), MSG_NOSIGNAL);
      }
      if (then == Then::Close) {
        // A moment first: the subscriber reads what it was sent before it meets the end.
        std::this_thread::sleep_for(std::chrono::milliseconds(200));
      } else {
        while (recv(peer, buffer, sizeof buffer, 0) > 0) {
        }
      }
      close(peer);
    });
  }
  ~ScriptedDaemon() {
    shutdown(listener_, SHUT_RDWR);  // an accept() still waiting returns
    thread_.join();
    close(listener_);
  }
  // The bytes of the subscriber's Hello (empty until it came).
  std::vector<unsigned char> hello() const {
    std::lock_guard lock(mutex_);
    return hello_;
  }
  uint16_t port = 0;

 private:
  std::vector<unsigned char> reply_;
  mutable std::mutex mutex_;
  std::vector<unsigned char> hello_;
  int listener_ = -1;
  std::thread thread_;
};

}  // namespace skinstream::test
