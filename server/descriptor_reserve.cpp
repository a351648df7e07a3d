#include "server/descriptor_reserve.h"

#include <fcntl.h>
#include <unistd.h>

namespace skinstream::server {

DescriptorReserve::DescriptorReserve() { restore(); }

DescriptorReserve::~DescriptorReserve() { release(); }

bool DescriptorReserve::release() {
  if (fd_ < 0) return false;
  ::close(fd_);
  fd_ = -1;
  return true;
}

void DescriptorReserve::restore() {
  if (fd_ < 0) fd_ = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
}

}  // namespace skinstream::server
