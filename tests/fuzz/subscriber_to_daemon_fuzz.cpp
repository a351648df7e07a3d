// What a subscriber sends the daemon (Hello, Ack), in versions 1 and 2, as the TCP session reads
// it: a stream cut by the StreamDecoder with the daemon's 1 kB limit on a message, each message
// decoded by its type in its version. Whatever the bytes, the decoder throws nothing but
// DecodeError, with a one-line reason.
#include <algorithm>

#include "fuzz/one_line_file_error.h"
#include "protocol/subscriber/subscriber_stream.h"

namespace subscriber = skinstream::subscriber;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const size_t piece = 1 + size % 32;  // from the length, so a seed stays a whole message
  subscriber::StreamDecoder decoder(1024);
  try {
    for (size_t fed = 0; fed < size; fed += piece) {
      decoder.feed({data + fed, std::min(piece, size - fed)});
      while (const auto message = decoder.next()) {
        if (message->type == subscriber::MessageType::Hello) {
          const subscriber::Hello hello = subscriber::decode_hello(message->payload, message->version);
          if (hello.subject.size() > subscriber::kMaxHelloString || hello.token.size() > subscriber::kMaxHelloString) std::abort();
        } else if (message->type == subscriber::MessageType::Ack) {
          subscriber::decode_ack(message->payload);
        }
      }
    }
  } catch (const subscriber::DecodeError& e) {
    skinstream::fuzz::expect_one_printable_line(e.what());
  }
  return 0;
}
