// What a receiver reads from a multicast group, from anyone on the LAN: the input cut into
// datagrams (each a 2-byte little-endian length, then that many bytes), fed to one
// DatagramReassembler 5 ms apart. Only DecodeError may be thrown, with a one-line reason; every
// message it completes has the size its datagrams said, and a fragment that did not complete one
// never reports one.
#include <cstdlib>
#include <cstring>

#include "fuzz/one_line_file_error.h"
#include "protocol/datagram_reassembler.h"

namespace subscriber = skinstream::subscriber;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  subscriber::DatagramReassembler reassembler({.stream_id = 0, .window = std::chrono::milliseconds(20)});
  subscriber::DatagramReassembler::Clock::time_point now{};
  for (size_t at = 0; at + 2 <= size;) {
    uint16_t length;
    std::memcpy(&length, data + at, 2);
    at += 2;
    const size_t n = std::min<size_t>(length, size - at);
    const std::span<const unsigned char> datagram(data + at, n);
    at += n;
    now += std::chrono::milliseconds(5);
    try {
      const auto message = reassembler.add(datagram, now);
      if (message && message->bytes.size() != message->header.message_bytes) std::abort();
    } catch (const subscriber::DecodeError& e) {
      skinstream::fuzz::expect_one_printable_line(e.what());
    }
  }
  return 0;
}
