#include "protocol/files/c3d_take_writer.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cstring>

#include "protocol/files/c3d_format.h"
#include "protocol/files/c3d_preamble.h"
#include "protocol/files/file_error.h"

namespace skinstream {
namespace {

static_assert(std::endian::native == std::endian::little,
              "the take writer stores Intel floats as they are in memory");

constexpr size_t kTakeSampleBytes = 16;  // x, y, z, residual: float storage
constexpr float kFloatStorageScale = -1.0f;

std::vector<uint8_t> take_preamble(const std::vector<std::string>& labels, double rate_hz, uint64_t frames,
                                   const std::string& path) {
  return c3d_preamble(C3dPointLayout{labels, rate_hz, 1, frames}, path, C3dWriteOptions{},
                      kFloatStorageScale);
}

std::string system_reason(int error) { return std::strerror(error); }

void put_float(uint8_t* out, float value) { std::memcpy(out, &value, sizeof value); }

}  // namespace

C3dTakeWriter::C3dTakeWriter(std::string path, std::vector<std::string> labels, double rate_hz)
    : path_(std::move(path)), labels_(std::move(labels)), rate_hz_(rate_hz) {
  if (!(rate_hz_ > 0.0)) throw FileError(path_, "take rate must be positive");
  const std::vector<uint8_t> preamble = take_preamble(labels_, rate_hz_, 0, path_);
  fd_ = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd_ < 0) throw FileError(path_, "cannot create: " + system_reason(errno));
  preamble_bytes_ = preamble.size();
  data_offset_ = preamble.size();
  write_all(preamble.data(), preamble.size(), 0, "preamble");
}

C3dTakeWriter::~C3dTakeWriter() {
  if (fd_ >= 0) ::close(fd_);
}

void C3dTakeWriter::append(std::span<const Vec3> points) {
  const size_t frame_bytes = kTakeSampleBytes * labels_.size();
  const size_t at = pending_.size();
  pending_.resize(at + frame_bytes);
  uint8_t* out = pending_.data() + at;
  for (size_t i = 0; i < labels_.size(); ++i, out += kTakeSampleBytes) {
    const bool present = i < points.size() && is_present(points[i]);
    for (int axis = 0; axis < 3; ++axis)
      put_float(out + 4 * axis, present ? static_cast<float>(points[i][axis]) : 0.0f);
    put_float(out + 12, present ? 0.0f : -1.0f);  // a negative residual marks a missing sample
  }
  ++queued_;
}

void C3dTakeWriter::commit() {
  if (fd_ < 0) throw FileError(path_, "take file is closed");
  if (queued_ == committed_) return;
  const uint64_t offset = data_offset_ + committed_ * kTakeSampleBytes * labels_.size();
  write_all(pending_.data(), pending_.size(), offset, "frames");
  if (::fdatasync(fd_) != 0) throw FileError(path_, "cannot sync frames: " + system_reason(errno));
  pending_.clear();  // keeps its capacity
  write_preamble(queued_);
  committed_ = queued_;
}

void C3dTakeWriter::close() {
  if (fd_ < 0) return;
  commit();
  const uint64_t end = data_offset_ + committed_ * kTakeSampleBytes * labels_.size();
  const uint64_t padded =
      (end + c3d_format::kBlockBytes - 1) / c3d_format::kBlockBytes * c3d_format::kBlockBytes;
  if (::ftruncate(fd_, static_cast<off_t>(padded)) != 0 || ::fsync(fd_) != 0)
    throw FileError(path_, "cannot finish: " + system_reason(errno));
  ::close(fd_);
  fd_ = -1;
}

void C3dTakeWriter::write_preamble(uint64_t frames) {
  const std::vector<uint8_t> preamble = take_preamble(labels_, rate_hz_, frames, path_);
  if (preamble.size() != preamble_bytes_)
    throw FileError(path_, "preamble changed size");  // cannot happen: values only
  write_all(preamble.data(), preamble.size(), 0, "preamble");
  if (::fsync(fd_) != 0) throw FileError(path_, "cannot sync the frame count: " + system_reason(errno));
}

void C3dTakeWriter::write_all(const uint8_t* data, size_t size, uint64_t offset, const char* what) {
  while (size > 0) {
    const ssize_t written = ::pwrite(fd_, data, size, static_cast<off_t>(offset));
    if (written < 0 && errno == EINTR) continue;
    if (written <= 0)
      throw FileError(
          path_, std::string("cannot write ") + what + ": " + system_reason(written < 0 ? errno : ENOSPC));
    data += written;
    offset += static_cast<uint64_t>(written);
    size -= static_cast<size_t>(written);
  }
}

uint64_t recover_c3d_take(const std::string& path, const std::vector<std::string>& labels, double rate_hz) {
  const std::vector<uint8_t> empty = take_preamble(labels, rate_hz, 0, path);
  const int fd = ::open(path.c_str(), O_RDWR | O_CLOEXEC);
  if (fd < 0) throw FileError(path, "cannot open: " + system_reason(errno));
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  struct stat info {};
  if (::fstat(fd, &info) != 0) throw FileError(path, "cannot stat: " + system_reason(errno));
  const auto size = static_cast<uint64_t>(info.st_size);
  // The same header words that do not depend on the count: processor, points, data start.
  uint8_t start[c3d_format::kBlockBytes];
  if (size < empty.size() || ::pread(fd, start, sizeof start, 0) != static_cast<ssize_t>(sizeof start) ||
      std::memcmp(start, empty.data(), 6) != 0 || std::memcmp(start + 16, empty.data() + 16, 2) != 0)
    throw FileError(path, "not a take file of these " + std::to_string(labels.size()) + " points");
  const uint64_t frame_bytes = kTakeSampleBytes * labels.size();
  uint64_t frames = frame_bytes ? (size - empty.size()) / frame_bytes : 0;
  // A frame of zero bytes was never written by the writer (a missing sample has residual -1):
  // it is the padding of a close, or pages a power loss left zeroed.
  std::vector<uint8_t> frame(frame_bytes);
  while (frames > 0) {
    const auto at = static_cast<off_t>(empty.size() + (frames - 1) * frame_bytes);
    if (::pread(fd, frame.data(), frame.size(), at) != static_cast<ssize_t>(frame.size()))
      throw FileError(path, "cannot read: " + system_reason(errno));
    if (std::any_of(frame.begin(), frame.end(), [](uint8_t b) { return b != 0; })) break;
    --frames;
  }
  const std::vector<uint8_t> preamble = take_preamble(labels, rate_hz, frames, path);
  const uint64_t end = empty.size() + frames * frame_bytes;
  const uint64_t padded =
      (end + c3d_format::kBlockBytes - 1) / c3d_format::kBlockBytes * c3d_format::kBlockBytes;
  if (::pwrite(fd, preamble.data(), preamble.size(), 0) != static_cast<ssize_t>(preamble.size()) ||
      ::ftruncate(fd, static_cast<off_t>(end)) != 0 || ::ftruncate(fd, static_cast<off_t>(padded)) != 0 ||
      ::fsync(fd) != 0)
    throw FileError(path, "cannot close the take: " + system_reason(errno));
  return frames;
}

}  // namespace skinstream
