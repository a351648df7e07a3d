#include "server/record/frame_table.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "protocol/files/file_error.h"
#include "protocol/files/whole_file.h"

namespace skinstream::server {

FrameTable::FrameTable(std::string path, const std::string& header) : path_(std::move(path)) {
  fd_ = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_APPEND | O_CLOEXEC, 0644);
  if (fd_ < 0) throw FileError(path_, std::string("cannot create: ") + std::strerror(errno));
  pending_.reserve(1 << 16);
  pending_ = header + "\n";
}

FrameTable::~FrameTable() {
  if (fd_ >= 0) ::close(fd_);
}

void FrameTable::commit() {
  if (fd_ < 0) throw FileError(path_, "table is closed");
  const char* data = pending_.data();
  size_t left = pending_.size();
  while (left > 0) {
    const ssize_t written = ::write(fd_, data, left);
    if (written < 0 && errno == EINTR) continue;
    if (written <= 0)
      throw FileError(path_, std::string("cannot write: ") + std::strerror(written < 0 ? errno : ENOSPC));
    data += written;
    left -= static_cast<size_t>(written);
  }
  pending_.clear();  // keeps its capacity
  if (::fdatasync(fd_) != 0) throw FileError(path_, std::string("cannot sync: ") + std::strerror(errno));
}

void FrameTable::close() {
  if (fd_ < 0) return;
  commit();
  ::close(fd_);
  fd_ = -1;
}

uint64_t recover_frame_table(const std::string& path) {
  const std::string text = read_whole_file(path);
  const size_t end = text.rfind('\n');
  const size_t keep = end == std::string::npos ? 0 : end + 1;
  if (keep != text.size() && ::truncate(path.c_str(), static_cast<off_t>(keep)) != 0)
    throw FileError(path, std::string("cannot cut the partial line: ") + std::strerror(errno));
  const auto lines =
      static_cast<uint64_t>(std::count(text.begin(), text.begin() + static_cast<long>(keep), '\n'));
  return lines > 0 ? lines - 1 : 0;  // the header is not a frame
}

}  // namespace skinstream::server
