#include "tcp_connection.h"

#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fcntl.h>

#include "skinstream/client.h"

namespace skinstream::client {
namespace {

int poll_milliseconds(std::chrono::milliseconds timeout) {
  return static_cast<int>(std::max<int64_t>(0, std::min<int64_t>(timeout.count(), 1 << 30)));
}

}  // namespace

TcpConnection::TcpConnection(const std::string& host, uint16_t port, std::chrono::milliseconds timeout)
    : peer_(host + ":" + std::to_string(port)) {
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* found = nullptr;
  const int resolved = ::getaddrinfo(host.c_str(), std::to_string(port).c_str(), &hints, &found);
  if (resolved != 0) throw Error(peer_ + ": " + ::gai_strerror(resolved));
  std::string last_error = "no address";
  for (addrinfo* a = found; a && fd_ < 0; a = a->ai_next) {
    const int fd = ::socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC, a->ai_protocol);
    if (fd < 0) {
      last_error = std::strerror(errno);
      continue;
    }
    // Non-blocking connect, so the timeout holds; blocking again afterwards.
    const int flags = ::fcntl(fd, F_GETFL, 0);
    ::fcntl(fd, F_SETFL, flags | O_NONBLOCK);
    int rc = ::connect(fd, a->ai_addr, a->ai_addrlen);
    if (rc != 0 && errno == EINPROGRESS) {
      pollfd p{fd, POLLOUT, 0};
      rc = ::poll(&p, 1, poll_milliseconds(timeout));
      if (rc == 0) {
        errno = ETIMEDOUT;
        rc = -1;
      } else if (rc > 0) {
        int error = 0;
        socklen_t length = sizeof error;
        ::getsockopt(fd, SOL_SOCKET, SO_ERROR, &error, &length);
        errno = error;
        rc = error == 0 ? 0 : -1;
      }
    }
    if (rc != 0) {
      last_error = std::strerror(errno);
      ::close(fd);
      continue;
    }
    ::fcntl(fd, F_SETFL, flags);
    const int one = 1;
    ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    fd_ = fd;
  }
  ::freeaddrinfo(found);
  if (fd_ < 0) throw Error(peer_ + ": " + last_error);
}

TcpConnection::~TcpConnection() {
  if (fd_ >= 0) ::close(fd_);
}

void TcpConnection::send_all(std::span<const unsigned char> bytes) {
  while (!bytes.empty()) {
    const ssize_t n = ::send(fd_, bytes.data(), bytes.size(), MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) throw Error(peer_ + ": sending failed: " + std::strerror(errno));
    bytes = bytes.subspan(static_cast<size_t>(n));
  }
}

size_t TcpConnection::receive(std::span<unsigned char> into, std::chrono::milliseconds timeout) {
  pollfd p{fd_, POLLIN, 0};
  int ready;
  do ready = ::poll(&p, 1, poll_milliseconds(timeout));
  while (ready < 0 && errno == EINTR);
  if (ready < 0) throw Error(peer_ + ": " + std::strerror(errno));
  if (ready == 0) return 0;
  ssize_t n;
  do n = ::recv(fd_, into.data(), into.size(), 0);
  while (n < 0 && errno == EINTR);
  if (n == 0) throw Error(peer_ + ": the daemon closed the connection");
  if (n < 0) throw Error(peer_ + ": " + std::strerror(errno));
  return static_cast<size_t>(n);
}

}  // namespace skinstream::client
