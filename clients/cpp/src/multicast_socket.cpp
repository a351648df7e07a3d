#include "multicast_socket.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <ctime>

#include "skinstream/client.h"

namespace skinstream::client {

MulticastSocket::MulticastSocket(const std::string& group, uint16_t port, const std::string& interface_address)
    : where_("multicast " + group + ":" + std::to_string(port)) {
  in_addr group_address{}, interface{};
  if (inet_pton(AF_INET, group.c_str(), &group_address) != 1 || !IN_MULTICAST(ntohl(group_address.s_addr)))
    throw Error(where_ + ": " + group + " is not an IPv4 multicast address (224.0.0.0-239.255.255.255)");
  if (inet_pton(AF_INET, interface_address.c_str(), &interface) != 1)
    throw Error(where_ + ": interface " + interface_address + " is not an IPv4 address");
  fd_ = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd_ < 0) throw Error(where_ + ": socket: " + std::strerror(errno));
  const int on = 1;
  // A few frames of room: the reader may be busy evaluating the previous frame when a burst comes.
  const int receive_buffer = 1 << 20;
  sockaddr_in bound{};
  bound.sin_family = AF_INET;
  bound.sin_addr = group_address;  // the group's datagrams only, not every datagram to this port
  bound.sin_port = htons(port);
  ip_mreq membership{};
  membership.imr_multiaddr = group_address;
  membership.imr_interface = interface;
  const char* failed = nullptr;
  if (setsockopt(fd_, SOL_SOCKET, SO_REUSEADDR, &on, sizeof on) != 0) failed = "allow several receivers on the port";
  else if (setsockopt(fd_, SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof on) != 0) failed = "ask for arrival times";
  else if (setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &receive_buffer, sizeof receive_buffer) != 0) failed = "size the receive buffer";
  else if (bind(fd_, reinterpret_cast<const sockaddr*>(&bound), sizeof bound) != 0) failed = "bind the port";
  else if (setsockopt(fd_, IPPROTO_IP, IP_ADD_MEMBERSHIP, &membership, sizeof membership) != 0)
    failed = "join the group on that interface (an address of this host?)";
  if (failed) {
    const std::string reason = std::strerror(errno);
    close(fd_);
    throw Error(where_ + ": cannot " + failed + ": " + reason);
  }
}

MulticastSocket::~MulticastSocket() { close(fd_); }

size_t MulticastSocket::receive(std::span<unsigned char> into, std::chrono::milliseconds timeout,
                                std::chrono::steady_clock::time_point& out_arrival) {
  pollfd p{fd_, POLLIN, 0};
  int ready;
  do ready = ::poll(&p, 1, static_cast<int>(std::clamp<int64_t>(timeout.count(), 0, 1 << 30)));
  while (ready < 0 && errno == EINTR);
  if (ready < 0) throw Error(where_ + ": " + std::strerror(errno));
  if (ready == 0) return 0;
  iovec piece{into.data(), into.size()};
  alignas(cmsghdr) unsigned char control[CMSG_SPACE(sizeof(timespec))];
  msghdr message{};
  message.msg_iov = &piece;
  message.msg_iovlen = 1;
  message.msg_control = control;
  message.msg_controllen = sizeof control;
  ssize_t n;
  do n = ::recvmsg(fd_, &message, MSG_DONTWAIT);
  while (n < 0 && errno == EINTR);
  if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return 0;
  if (n < 0) throw Error(where_ + ": " + std::strerror(errno));
  const auto now = std::chrono::steady_clock::now();
  out_arrival = now;
  for (cmsghdr* c = CMSG_FIRSTHDR(&message); c; c = CMSG_NXTHDR(&message, c)) {
    if (c->cmsg_level != SOL_SOCKET || c->cmsg_type != SCM_TIMESTAMPNS) continue;
    timespec received;
    std::memcpy(&received, CMSG_DATA(c), sizeof received);
    // The kernel stamps the system clock: its age, taken from the steady clock's now.
    const auto age = std::chrono::system_clock::now().time_since_epoch() -
                     (std::chrono::seconds(received.tv_sec) + std::chrono::nanoseconds(received.tv_nsec));
    if (age > std::chrono::nanoseconds(0)) out_arrival = now - std::chrono::duration_cast<std::chrono::steady_clock::duration>(age);
  }
  return static_cast<size_t>(n);
}

}  // namespace skinstream::client
