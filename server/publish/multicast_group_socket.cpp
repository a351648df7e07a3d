#include "server/publish/multicast_group_socket.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace skinstream::server {

std::string describe(const MulticastGroupAddress& a) {
  return "multicast " + a.group + ":" + std::to_string(a.port);
}

int open_multicast_group_socket(const MulticastGroupAddress& a) {
  in_addr group{}, interface {};
  if (inet_pton(AF_INET, a.group.c_str(), &group) != 1 || !IN_MULTICAST(ntohl(group.s_addr)))
    throw std::runtime_error(describe(a) + ": " + a.group +
                             " is not an IPv4 multicast address (224.0.0.0-239.255.255.255)");
  if (inet_pton(AF_INET, a.interface_address.c_str(), &interface) != 1)
    throw std::runtime_error(describe(a) + ": interface " + a.interface_address + " is not an IPv4 address");
  if (a.ttl < 0 || a.ttl > 255) throw std::runtime_error(describe(a) + ": ttl must be 0-255");
  const int fd = socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0) throw std::runtime_error(describe(a) + ": socket: " + std::strerror(errno));
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_addr = group;
  to.sin_port = htons(a.port);
  const int ttl = a.ttl;
  const char* failed = nullptr;
  if (setsockopt(fd, IPPROTO_IP, IP_MULTICAST_TTL, &ttl, sizeof ttl) != 0)
    failed = "the TTL";
  else if (interface.s_addr != INADDR_ANY &&
           setsockopt(fd, IPPROTO_IP, IP_MULTICAST_IF, &interface, sizeof interface) != 0)
    failed = "the interface (an address of this host?)";
  else if (connect(fd, reinterpret_cast<const sockaddr*>(&to), sizeof to) != 0)
    failed = "the group (a route to it?)";
  if (failed) {
    const std::string reason = std::strerror(errno);
    close(fd);
    throw std::runtime_error(describe(a) + ": cannot set " + failed + ": " + reason);
  }
  return fd;
}

GroupSend send_to_group(int fd, mmsghdr* datagrams, size_t count) {
  GroupSend result;
  while (result.sent < count) {
    const int n =
        sendmmsg(fd, datagrams + result.sent, static_cast<unsigned>(count - result.sent), MSG_DONTWAIT);
    if (n > 0) {
      result.sent += static_cast<size_t>(n);
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == ENOBUFS))
      result.buffer_full = true;
    else
      result.error = n < 0 ? errno : EIO;
    break;
  }
  return result;
}

}  // namespace skinstream::server
