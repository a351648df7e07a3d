#pragma once
// The socket the daemon sends to a multicast group with: UDP, non-blocking (the pipeline thread
// never waits on it), connected to group:port, with the TTL and the interface to send from.
// Shared by the frames (MulticastSender) and the offer (MulticastOffer).

#include <sys/socket.h>

#include <cstddef>
#include <cstdint>
#include <string>

namespace skinstream::server {

struct MulticastGroupAddress {
  std::string group;  // IPv4 multicast address (224.0.0.0/4)
  uint16_t port = 0;
  std::string interface_address = "0.0.0.0";  // this host's address to send from; 0.0.0.0: the system's route
  int ttl = 1;                                // 1: the link only
};

// "multicast GROUP:PORT", for messages.
std::string describe(const MulticastGroupAddress& address);
// The socket's descriptor (the caller closes it). Throws std::runtime_error with one line: a bad
// group or interface, a TTL out of 0-255, no socket, no route.
int open_multicast_group_socket(const MulticastGroupAddress& address);

// Hands `count` datagrams to the non-blocking socket `fd` (sendmmsg, again after EINTR and after
// taking some), never waiting. What it took, and when it stopped short, why: `buffer_full`
// (EAGAIN, ENOBUFS: the datagrams left are dropped) or `error` (an errno).
struct GroupSend {
  size_t sent = 0;
  bool buffer_full = false;
  int error = 0;
};
GroupSend send_to_group(int fd, mmsghdr* datagrams, size_t count);

}  // namespace skinstream::server
