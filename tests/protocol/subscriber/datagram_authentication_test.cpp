// The multicast datagrams' HMAC-SHA-256: RFC 4231's test vectors (a key of the block size and
// one longer, hashed first), the same tags as OpenSSL's own HMAC() over parts cut anywhere, a
// verify that refuses a changed byte or a tag of the wrong size, short keys refused, and key files.
#include "protocol/subscriber/datagram_authentication.h"

#include <gtest/gtest.h>
#include <openssl/evp.h>
#include <openssl/hmac.h>

#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "support/allocation_counter.h"
#include "support/test_data.h"

namespace skinstream::subscriber {
namespace {

std::vector<unsigned char> bytes(const std::string& text) { return {text.begin(), text.end()}; }

std::string hex(std::span<const unsigned char> data) {
  static const char* digits = "0123456789abcdef";
  std::string out;
  for (unsigned char b : data) out += {digits[b >> 4], digits[b & 15]};
  return out;
}

TEST(DatagramAuthentication, MatchesRfc4231) {
  const std::vector<unsigned char> key1(20, 0x0b), data1 = bytes("Hi There");
  const std::span<const unsigned char> parts1[] = {data1};
  EXPECT_EQ(hex(DatagramAuthenticator(key1).tag(parts1)), "b0344c61d8db38535ca8afceaf0bf12b881dc200c9833da726e9376c2e32cff7");
  const std::vector<unsigned char> key6(131, 0xaa), data6 = bytes("Test Using Larger Than Block-Size Key - Hash Key First");
  const std::span<const unsigned char> parts6[] = {data6};
  EXPECT_EQ(hex(DatagramAuthenticator(key6).tag(parts6)), "60e431591ee0b67f0d8a26aacbf5b77f8e0bc6213728c5140546040f0ee37f54");
}

TEST(DatagramAuthentication, EqualsOpenSslsHmacOverPartsCutAnywhereWithoutAllocating) {
  std::mt19937 random(11);
  std::vector<unsigned char> key(37), data(1400);
  for (auto& b : key) b = static_cast<unsigned char>(random());
  for (auto& b : data) b = static_cast<unsigned char>(random());
  const DatagramAuthenticator authenticator(key);
  unsigned char expected[EVP_MAX_MD_SIZE];
  unsigned int expected_size = 0;
  HMAC(EVP_sha256(), key.data(), static_cast<int>(key.size()), data.data(), data.size(), expected, &expected_size);
  ASSERT_EQ(expected_size, kDatagramTagBytes);
  const test::CountAllocations allocations;
  for (const size_t cut : {size_t{0}, size_t{28}, size_t{700}, size_t{1400}}) {
    const std::span<const unsigned char> parts[] = {std::span(data).first(cut), std::span(data).subspan(cut)};
    const DatagramTag tag = authenticator.tag(parts);
    EXPECT_TRUE(std::equal(tag.begin(), tag.end(), expected)) << "cut at " << cut;
    EXPECT_TRUE(authenticator.verify(parts, std::span(expected, expected_size)));
  }
  EXPECT_EQ(allocations.count(), 0u);
  const std::span<const unsigned char> whole[] = {data};
  DatagramTag changed;
  std::copy(expected, expected + expected_size, changed.begin());
  changed[31] ^= 0x80;
  EXPECT_FALSE(authenticator.verify(whole, changed));
  EXPECT_FALSE(authenticator.verify(whole, std::span(expected, 16)));
  data[100] ^= 1;
  EXPECT_FALSE(authenticator.verify(whole, std::span(expected, expected_size)));
}

TEST(DatagramAuthentication, ShortKeysAndBadKeyFilesAreRefused) {
  EXPECT_THROW(DatagramAuthenticator(bytes("fifteen bytes!!")), std::invalid_argument);
  EXPECT_NO_THROW(DatagramAuthenticator(bytes("sixteen bytes!!!")));
  const std::string good = test::scratch_path("multicast_key.txt"), short_key = test::scratch_path("multicast_short_key.txt");
  std::ofstream(good) << "stage-7 multicast key\r\nnot part of it\n";
  std::ofstream(short_key) << "too short\n";
  EXPECT_EQ(read_datagram_key_file(good), bytes("stage-7 multicast key"));
  try {
    read_datagram_key_file(short_key);
    FAIL() << "a short key was read";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(short_key + ": the multicast key's first line has 9 bytes; at least 16"), std::string::npos) << e.what();
  }
  EXPECT_THROW(read_datagram_key_file(test::scratch_path("no_such_key.txt")), std::runtime_error);
}

}  // namespace
}  // namespace skinstream::subscriber
