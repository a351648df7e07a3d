#pragma once
// The subscriber protocol's golden messages (tests/protocol/fixtures/subscriber/, written byte by
// byte from the specification, independently of the encoder) and a message's payload.
#include <span>
#include <string>
#include <vector>

#include "protocol/subscriber/subscriber_stream.h"
#include "support/fixture_bytes.h"

namespace skinstream::test {

inline ByteVector subscriber_fixture(const std::string& name) { return fixture_bytes("subscriber/" + name); }

inline std::span<const unsigned char> payload_of(const std::vector<unsigned char>& message) {
  return std::span<const unsigned char>(message).subspan(subscriber::kHeaderBytes);
}

}  // namespace skinstream::test
