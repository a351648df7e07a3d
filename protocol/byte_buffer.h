#pragma once
// Little-endian byte writing and bounds-checked reading for the project's binary formats.
// A read past the end throws std::out_of_range; callers turn that into a FileError.

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <stdexcept>
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

class ByteReader {
 public:
  ByteReader(const unsigned char* data, size_t size) : data_(data), size_(size) {}
  template <typename T>
  T get() {
    static_assert(std::is_arithmetic_v<T>);
    need(sizeof(T));
    T value;
    std::memcpy(&value, data_ + pos_, sizeof(T));
    pos_ += sizeof(T);
    return value;
  }
  std::string get_string(size_t max_length = 1 << 20) {
    const uint32_t n = get<uint32_t>();
    if (n > max_length) throw std::out_of_range("string of " + std::to_string(n) + " bytes is implausible");
    need(n);
    std::string s(reinterpret_cast<const char*>(data_ + pos_), n);
    pos_ += n;
    return s;
  }
  // A count that must fit in what is left, given the bytes each item takes at least.
  uint32_t get_count(size_t min_item_bytes) {
    const uint32_t n = get<uint32_t>();
    if (min_item_bytes > 0 && n > remaining() / min_item_bytes)
      throw std::out_of_range("count " + std::to_string(n) + " exceeds the data left");
    return n;
  }
  // `count` values at once: one bounds check and one copy (the stream's byte order is the host's,
  // little-endian, as for get()). No values may come with no storage (an empty vector's data()):
  // memcpy must not be given a null pointer, even for 0 bytes.
  template <typename T>
  void get_array(T* out, size_t count) {
    static_assert(std::is_arithmetic_v<T>);
    if (count > (size_ - pos_) / sizeof(T)) throw std::out_of_range("truncated at byte " + std::to_string(pos_));
    if (count == 0) return;
    std::memcpy(out, data_ + pos_, count * sizeof(T));
    pos_ += count * sizeof(T);
  }
  void skip(size_t n) {
    need(n);
    pos_ += n;
  }
  size_t remaining() const { return size_ - pos_; }
  size_t position() const { return pos_; }

 private:
  void need(size_t n) const {
    if (n > size_ - pos_) throw std::out_of_range("truncated at byte " + std::to_string(pos_));
  }
  const unsigned char* data_;
  size_t size_;
  size_t pos_ = 0;
};

// Fixed layouts whose size the caller has already checked (a header, a block of known length):
// one value written or read at a cursor, which moves past it. Host byte order, little-endian.
template <typename T>
void put_at(unsigned char*& at, T value) {
  static_assert(std::is_arithmetic_v<T>);
  std::memcpy(at, &value, sizeof(T));
  at += sizeof(T);
}
template <typename T>
T get_at(const unsigned char*& at) {
  static_assert(std::is_arithmetic_v<T>);
  T value;
  std::memcpy(&value, at, sizeof(T));
  at += sizeof(T);
  return value;
}

// The zero bytes that bring n bytes to a multiple of 4 (blocks of the subscriber protocol start
// 4-aligned).
constexpr size_t padding_to_4(size_t n) { return (4 - n % 4) % 4; }

// CRC-32 (IEEE 802.3, reflected), to reject corrupted files.
uint32_t crc32(const unsigned char* data, size_t size);

}  // namespace skinstream
