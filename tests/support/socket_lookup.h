#pragma once
// For tests that run a server in-process: the server's end of a loopback connection, found by
// its addresses among /proc/self/fd, so a test can read what the server set on its socket.

#include <arpa/inet.h>
#include <sys/socket.h>

#include <filesystem>
#include <string>

#include "server/asio.h"

namespace skinstream::test {

// This process's other end of `client`'s connection; -1 if there is none.
inline int server_side_of(const server::tcp::socket& client) {
  const server::tcp::endpoint local = client.local_endpoint(), remote = client.remote_endpoint();
  for (const auto& entry : std::filesystem::directory_iterator("/proc/self/fd")) {
    const int fd = std::stoi(entry.path().filename().string());
    sockaddr_in own{}, peer{};
    socklen_t own_length = sizeof own, peer_length = sizeof peer;
    if (::getsockname(fd, reinterpret_cast<sockaddr*>(&own), &own_length) != 0 || own.sin_family != AF_INET) continue;
    if (::getpeername(fd, reinterpret_cast<sockaddr*>(&peer), &peer_length) != 0) continue;
    if (ntohs(own.sin_port) == remote.port() && ntohs(peer.sin_port) == local.port()) return fd;
  }
  return -1;
}

}  // namespace skinstream::test
