#pragma once
// Little-endian byte writing into a growing buffer for the project's binary formats, and what
// every format shares (padding, CRC-32). Reading: protocol/byte_reader.h; writing into a span of
// known size: protocol/span_writer.h.

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

namespace skinstream {

class ByteWriter {
 public:
  template <typename T>
  void put(T value) {
    static_assert(std::is_arithmetic_v<T>);
    unsigned char raw[sizeof(T)];
    std::memcpy(raw, &value, sizeof(T));
    bytes_.insert(bytes_.end(), raw, raw + sizeof(T));  // the project only targets little-endian hosts
  }
  void put_string(const std::string& s) {
    put<uint32_t>(static_cast<uint32_t>(s.size()));
    bytes_.insert(bytes_.end(), s.begin(), s.end());
  }
  void put_bytes(const void* data, size_t size) {
    if (size == 0) return;
    const auto* p = static_cast<const unsigned char*>(data);
    bytes_.insert(bytes_.end(), p, p + size);
  }
  const std::vector<unsigned char>& bytes() const { return bytes_; }
  std::vector<unsigned char>& bytes() { return bytes_; }

 private:
  std::vector<unsigned char> bytes_;
};

// The zero bytes that bring n bytes to a multiple of 4 (blocks of the subscriber protocol start
// 4-aligned).
constexpr size_t padding_to_4(size_t n) { return (4 - n % 4) % 4; }

// CRC-32 (IEEE 802.3, reflected), to reject corrupted files.
uint32_t crc32(const unsigned char* data, size_t size);

}  // namespace skinstream
