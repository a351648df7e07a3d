#pragma once
// The one bounds-checked reader of the project's binary formats and protocols, with errors as
// values: a read that does not fit never throws. The first failure is kept (a ByteError naming
// the field and the offset) and sticks: every later read returns zero, an empty span or false,
// so a decoder reads its fields in a row and asks ok() once. Nothing here allocates (but the
// error's message(), made once a failure is reported).
// Values are copied as they are: every format read is little-endian, and so is the host.

#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <type_traits>

namespace skinstream {

static_assert(std::endian::native == std::endian::little,
              "the formats read are little-endian; a big-endian host must swap");

// Why a read failed: `wanted` bytes for `field` at byte `offset`, where `available` were left.
// A count whose items cannot fit is reported as the bytes its items need at the least.
struct ByteError {
  const char* field = nullptr;  // null while nothing failed
  size_t offset = 0;
  size_t wanted = 0;
  size_t available = 0;

  explicit operator bool() const { return field != nullptr; }
  // "truncated in FIELD: needs WANTED bytes at offset OFFSET, AVAILABLE left"
  std::string message() const {
    return std::string("truncated in ") + (field ? field : "nothing") + ": needs " + std::to_string(wanted) +
           " bytes at offset " + std::to_string(offset) + ", " + std::to_string(available) + " left";
  }
};

class ByteReader {
 public:
  ByteReader() = default;
  ByteReader(const unsigned char* data, size_t size) : data_(data), size_(size) {}
  explicit ByteReader(std::span<const unsigned char> bytes) : data_(bytes.data()), size_(bytes.size()) {}

  // One value; zero once anything failed.
  template <typename T>
  T get(const char* field) {
    static_assert(std::is_arithmetic_v<T>);
    T value{};
    if (!need(sizeof(T), field)) return value;
    std::memcpy(&value, data_ + pos_, sizeof(T));
    pos_ += sizeof(T);
    return value;
  }
  // The same into `out`, for chains of reads: false once anything failed (`out` then untouched).
  template <typename T>
  bool read(T& out, const char* field) {
    static_assert(std::is_arithmetic_v<T>);
    if (!need(sizeof(T), field)) return false;
    std::memcpy(&out, data_ + pos_, sizeof(T));
    pos_ += sizeof(T);
    return true;
  }
  // `count` values at once: one bounds check, one copy. No values may come with no storage (an
  // empty vector's data() is null, which memcpy must not be given even for 0 bytes).
  template <typename T>
  bool get_array(T* out, size_t count, const char* field) {
    static_assert(std::is_arithmetic_v<T>);
    if (!ok()) return false;
    if (count > remaining() / sizeof(T)) return fail(field, count * sizeof(T));
    if (count == 0) return true;
    std::memcpy(out, data_ + pos_, count * sizeof(T));
    pos_ += count * sizeof(T);
    return true;
  }
  // The next n bytes, in place; empty once anything failed.
  std::span<const unsigned char> take(size_t n, const char* field) {
    if (!need(n, field)) return {};
    const std::span<const unsigned char> bytes(data_ + pos_, n);
    pos_ += n;
    return bytes;
  }
  bool skip(size_t n, const char* field) {
    if (!need(n, field)) return false;
    pos_ += n;
    return true;
  }
  // A u32 count of items that take min_item_bytes each at the least, which must fit in what is
  // left; 0 (and a failure) when they cannot.
  uint32_t get_count(size_t min_item_bytes, const char* field) {
    const uint32_t n = get<uint32_t>(field);
    if (min_item_bytes > 0 && n > remaining() / min_item_bytes) {
      fail(field, n * min_item_bytes);
      return 0;
    }
    return n;
  }
  // Records a failure of `wanted` bytes for `field` at the position (the first one is kept);
  // returns false. A decoder that finds a value out of bounds stops the reader with wanted = 0
  // (and keeps its own text for it).
  bool fail(const char* field, size_t wanted) {
    if (!error_) error_ = ByteError{field, pos_, wanted, remaining()};
    return false;
  }

  bool ok() const { return !error_; }
  const ByteError& error() const { return error_; }
  size_t remaining() const { return size_ - pos_; }
  size_t position() const { return pos_; }
  size_t size() const { return size_; }
  // The bytes not read yet (for a look ahead, or text scanned in place).
  const unsigned char* here() const { return data_ + pos_; }

 private:
  bool need(size_t n, const char* field) {
    if (!ok()) return false;
    if (n > remaining()) return fail(field, n);
    return true;
  }
  const unsigned char* data_ = nullptr;
  size_t size_ = 0;
  size_t pos_ = 0;
  ByteError error_;
};

}  // namespace skinstream
