#pragma once
// Writes little-endian values at a cursor in a caller's span of known size (a header, a frame):
// no allocation, no bounds check, the caller having sized the span. The host's byte order is the
// formats', so values are copied as they are.

#include <bit>
#include <cstddef>
#include <cstring>
#include <span>
#include <type_traits>

namespace skinstream {

static_assert(std::endian::native == std::endian::little,
              "the formats written are little-endian; a big-endian host must swap");

class SpanWriter {
 public:
  explicit SpanWriter(std::span<unsigned char> out) : out_(out) {}
  template <typename T>
  void put(T value) {
    static_assert(std::is_arithmetic_v<T>);
    std::memcpy(out_.data() + pos_, &value, sizeof(T));
    pos_ += sizeof(T);
  }
  // A whole array in one copy: value by value, the compiler must assume each byte written may
  // be the cursor itself and reload it, which made the 640 kB of a mesh's positions a scalar loop.
  template <typename T>
  void put_array(std::span<const T> values) {
    static_assert(std::is_arithmetic_v<T>);
    if (values.empty()) return;  // its data() may be null, which memcpy must not be given
    std::memcpy(out_.data() + pos_, values.data(), values.size_bytes());
    pos_ += values.size_bytes();
  }
  // The next n bytes, for the caller to fill; the cursor moves past them.
  unsigned char* reserve(size_t n) {
    unsigned char* at = out_.data() + pos_;
    pos_ += n;
    return at;
  }
  void zeros(size_t n) {
    if (n == 0) return;
    std::memset(out_.data() + pos_, 0, n);
    pos_ += n;
  }
  size_t position() const { return pos_; }

 private:
  std::span<unsigned char> out_;
  size_t pos_ = 0;
};

}  // namespace skinstream
