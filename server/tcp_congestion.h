#pragma once
// The TCP congestion control of one socket (Linux TCP_CONGESTION). Why the daemon sets it on
// the sockets it publishes frames on: under BBR, the default on some hosts, Linux paces every
// send, so a 640 kB frame leaves over up to a third of a millisecond of pacing timers instead
// of at once, and on loopback the four subscribers' deliveries took twice as long (measured in
// the README).
// Reno and CUBIC do not pace; reno is the one any process may choose (CAP_NET_ADMIN is needed
// for those not in /proc/sys/net/ipv4/tcp_allowed_congestion_control).

#include <string>

namespace skinstream::server {

// Sets `algorithm` ("reno", "cubic", ...) on a TCP socket. Returns an empty string on success,
// otherwise why not (the socket keeps the one it had and stays usable).
std::string set_tcp_congestion(int socket_handle, const std::string& algorithm);

// The socket's congestion control, or an empty string when it cannot be read.
std::string tcp_congestion_of(int socket_handle);

// The name is one Linux could know: 1-15 characters of a-z, 0-9, '_' and '-'.
bool is_tcp_congestion_name(const std::string& algorithm);

// What new TCP sockets get on this machine (/proc/sys/net/ipv4/tcp_congestion_control); empty
// when it cannot be read.
std::string system_tcp_congestion();

// For a server's accept handler (one thread): sets `algorithm` on every accepted socket, and the
// first time the kernel refuses it logs why, naming `who`; the sockets then keep the system's.
// An empty algorithm does nothing.
class AcceptedSocketCongestion {
 public:
  AcceptedSocketCongestion(std::string who, std::string algorithm) : who_(std::move(who)), algorithm_(std::move(algorithm)) {}
  void apply(int socket_handle);

 private:
  std::string who_, algorithm_;
  bool refusal_said_ = false;
};

}  // namespace skinstream::server
