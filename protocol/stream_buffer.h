#pragma once
// The bytes of a stream (a TCP connection) that have arrived and are not cut into messages yet:
// what the stream cutters of every protocol share (the Vicon and QTM RT packet framers, the
// subscriber protocol's StreamDecoder). A socket reads straight into prepare()'s room; the
// cutter looks at unread(), and consume()s each whole message it cuts. The unread tail (at most
// one partial message) moves to the front only when the room asked for does not fit behind it,
// and the storage grows only when it does not fit at all: a stream of messages of steady size
// stops allocating.

#include <algorithm>
#include <cstddef>
#include <span>
#include <vector>

namespace skinstream {

class StreamBuffer {
 public:
  // Room for `bytes` more at the end; then commit() what was written into it. Invalidates what
  // unread() gave.
  std::span<unsigned char> prepare(size_t bytes) {
    if (begin_ == end_) begin_ = end_ = 0;  // everything was cut: start at the front for free
    if (storage_.size() - end_ < bytes) {
      std::copy(storage_.begin() + static_cast<std::ptrdiff_t>(begin_),
                storage_.begin() + static_cast<std::ptrdiff_t>(end_), storage_.begin());
      end_ -= begin_;
      begin_ = 0;
      if (storage_.size() - end_ < bytes) storage_.resize(end_ + bytes);
    }
    return std::span(storage_).subspan(end_, bytes);
  }
  void commit(size_t bytes) { end_ += std::min(bytes, storage_.size() - end_); }
  // prepare() + copy + commit().
  void feed(std::span<const unsigned char> bytes) {
    const std::span<unsigned char> room = prepare(bytes.size());
    std::copy(bytes.begin(), bytes.end(), room.begin());
    commit(bytes.size());
  }

  // What arrived and was not consumed, valid until the next prepare() or feed().
  std::span<const unsigned char> unread() const { return std::span(storage_).subspan(begin_, end_ - begin_); }
  void consume(size_t bytes) { begin_ += std::min(bytes, end_ - begin_); }

  // Sizes the storage now, and writes it (its pages resident before the stream starts): room
  // asked for later of at most `bytes` less the unread tail never grows it.
  void reserve(size_t bytes) {
    if (storage_.size() < bytes) storage_.resize(bytes);
  }
  size_t buffered() const { return end_ - begin_; }
  size_t capacity() const { return storage_.size(); }
  void clear() { begin_ = end_ = 0; }

 private:
  std::vector<unsigned char> storage_;
  size_t begin_ = 0;  // the first byte not consumed
  size_t end_ = 0;    // one past the last byte committed
};

}  // namespace skinstream
