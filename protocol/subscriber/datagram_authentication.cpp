#include "protocol/subscriber/datagram_authentication.h"

// The one-shot and EVP interfaces make a context for every tag (an allocation on the daemon's
// pipeline thread); the SHA-256 state is a plain struct that can be copied instead.
#define OPENSSL_SUPPRESS_DEPRECATED
#include <openssl/crypto.h>
#include <openssl/sha.h>

#include <fstream>
#include <stdexcept>

namespace skinstream::subscriber {

struct DatagramAuthenticator::States {
  SHA256_CTX inner, outer;
};

DatagramAuthenticator::DatagramAuthenticator(std::span<const unsigned char> key) : states_(new States) {
  if (key.size() < kMinDatagramKeyBytes) {
    delete states_;
    throw std::invalid_argument("a multicast key of " + std::to_string(key.size()) + " bytes: at least " +
                                std::to_string(kMinDatagramKeyBytes) + " are needed");
  }
  // RFC 2104: a key longer than the block is hashed first; then padded with zeros to the block.
  std::array<unsigned char, SHA256_CBLOCK> block{};
  if (key.size() > block.size()) SHA256(key.data(), key.size(), block.data());
  else std::copy(key.begin(), key.end(), block.begin());
  std::array<unsigned char, SHA256_CBLOCK> pad;
  for (size_t i = 0; i < pad.size(); ++i) pad[i] = block[i] ^ 0x36;
  SHA256_Init(&states_->inner);
  SHA256_Update(&states_->inner, pad.data(), pad.size());
  for (size_t i = 0; i < pad.size(); ++i) pad[i] = block[i] ^ 0x5c;
  SHA256_Init(&states_->outer);
  SHA256_Update(&states_->outer, pad.data(), pad.size());
  OPENSSL_cleanse(block.data(), block.size());
  OPENSSL_cleanse(pad.data(), pad.size());
}

DatagramAuthenticator::~DatagramAuthenticator() {
  OPENSSL_cleanse(states_, sizeof *states_);
  delete states_;
}

DatagramTag DatagramAuthenticator::tag(std::span<const std::span<const unsigned char>> parts) const {
  SHA256_CTX context = states_->inner;
  for (const std::span<const unsigned char> part : parts) SHA256_Update(&context, part.data(), part.size());
  std::array<unsigned char, SHA256_DIGEST_LENGTH> inner;
  SHA256_Final(inner.data(), &context);
  context = states_->outer;
  SHA256_Update(&context, inner.data(), inner.size());
  DatagramTag out;
  SHA256_Final(out.data(), &context);
  return out;
}

void check_datagram_tag(const DatagramAuthenticator& authenticator, std::span<const unsigned char> datagram,
                        const DatagramHeader& header) {
  if (!header.authenticated) throw DecodeError("a datagram without a tag, and this receiver has a key");
  const std::span<const unsigned char> signed_parts[] = {
      datagram.first(datagram.size() - kDatagramTrailerBytes)};
  if (!authenticator.verify(signed_parts, datagram.last(kDatagramTrailerBytes)))
    throw DecodeError("a datagram whose tag is not the key's (forged, or sent with another key)");
}

bool DatagramAuthenticator::verify(std::span<const std::span<const unsigned char>> parts, std::span<const unsigned char> given) const {
  if (given.size() != kDatagramTagBytes) return false;
  const DatagramTag expected = tag(parts);
  return CRYPTO_memcmp(expected.data(), given.data(), kDatagramTagBytes) == 0;
}

std::vector<unsigned char> read_datagram_key_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open the multicast key file");
  std::string line;
  std::getline(in, line);
  if (!line.empty() && line.back() == '\r') line.pop_back();
  if (line.size() < kMinDatagramKeyBytes)
    throw std::runtime_error(path + ": the multicast key's first line has " + std::to_string(line.size()) + " bytes; at least " +
                             std::to_string(kMinDatagramKeyBytes) + " are needed");
  return {line.begin(), line.end()};
}

}  // namespace skinstream::subscriber
