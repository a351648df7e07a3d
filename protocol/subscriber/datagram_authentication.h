#pragma once
// HMAC-SHA-256 of the multicast datagrams (docs/subscriber-protocol.md, "Multicast"), keyed by a
// secret the daemon and its receivers share: a receiver given the key takes only datagrams whose
// tag it computes again, so nobody on the LAN can forge a frame, a sequence number or a model id.
// SHA-256 is OpenSSL's (libcrypto). The key's inner and outer blocks are hashed once, when the
// key is set; a tag then costs two copies of a SHA-256 state and the hashing of the datagram, and
// allocates nothing (the daemon signs on its pipeline thread).

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "protocol/subscriber/multicast_datagram.h"

namespace skinstream::subscriber {

inline constexpr size_t kDatagramTagBytes = kDatagramTrailerBytes;
using DatagramTag = std::array<unsigned char, kDatagramTagBytes>;

class DatagramAuthenticator {
 public:
  // `key`: any bytes, at least 16 (throws std::invalid_argument otherwise).
  explicit DatagramAuthenticator(std::span<const unsigned char> key);
  ~DatagramAuthenticator();
  DatagramAuthenticator(const DatagramAuthenticator&) = delete;
  DatagramAuthenticator& operator=(const DatagramAuthenticator&) = delete;

  // HMAC-SHA-256 of the bytes of `parts`, one after the other.
  DatagramTag tag(std::span<const std::span<const unsigned char>> parts) const;
  // Whether `given` is the tag of `parts`, compared in time that does not depend on the bytes.
  bool verify(std::span<const std::span<const unsigned char>> parts, std::span<const unsigned char> given) const;

 private:
  struct States;  // the SHA-256 states after the key's inner and outer blocks
  States* states_;
};

// Throws DecodeError unless `datagram` (whose header is `header`) carries the tag `authenticator`
// computes for its header and fragment.
void check_datagram_tag(const DatagramAuthenticator& authenticator, std::span<const unsigned char> datagram,
                        const DatagramHeader& header);

inline constexpr size_t kMinDatagramKeyBytes = 16;

// A key file's bytes: its first line, at least kMinDatagramKeyBytes long (a passphrase or hex).
// Throws std::runtime_error naming the file and what is wrong.
std::vector<unsigned char> read_datagram_key_file(const std::string& path);

}  // namespace skinstream::subscriber
