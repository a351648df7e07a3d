#include "server/tcp_unsent_limit.h"

#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/socket.h>

#include <cerrno>
#include <cstring>

namespace skinstream::server {

std::string set_tcp_unsent_limit(int socket_handle, int bytes) {
  if (setsockopt(socket_handle, IPPROTO_TCP, TCP_NOTSENT_LOWAT, &bytes, sizeof bytes) == 0) return {};
  return std::string("TCP_NOTSENT_LOWAT ") + std::to_string(bytes) + ": " + std::strerror(errno);
}

int tcp_unsent_limit_of(int socket_handle) {
  int bytes = 0;
  socklen_t size = sizeof bytes;
  if (getsockopt(socket_handle, IPPROTO_TCP, TCP_NOTSENT_LOWAT, &bytes, &size) != 0) return -1;
  return bytes;
}

}  // namespace skinstream::server
