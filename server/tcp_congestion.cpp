#include "server/tcp_congestion.h"

#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/socket.h>

#include <spdlog/spdlog.h>

#include <cerrno>
#include <cstring>
#include <fstream>

namespace skinstream::server {

std::string set_tcp_congestion(int socket_handle, const std::string& algorithm) {
  if (::setsockopt(socket_handle, IPPROTO_TCP, TCP_CONGESTION, algorithm.data(), static_cast<socklen_t>(algorithm.size())) == 0)
    return {};
  const int error = errno;
  std::string reason = std::strerror(error);
  if (error == EPERM)
    reason += " (without CAP_NET_ADMIN a process may use only those in /proc/sys/net/ipv4/tcp_allowed_congestion_control)";
  else if (error == ENOENT)
    reason += " (not in /proc/sys/net/ipv4/tcp_available_congestion_control)";
  return reason;
}

std::string tcp_congestion_of(int socket_handle) {
  char name[32] = {};
  socklen_t length = sizeof name;
  if (::getsockopt(socket_handle, IPPROTO_TCP, TCP_CONGESTION, name, &length) != 0) return {};
  return std::string(name, ::strnlen(name, length));
}

bool is_tcp_congestion_name(const std::string& algorithm) {
  if (algorithm.empty() || algorithm.size() > 15) return false;  // TCP_CA_NAME_MAX is 16 with the NUL
  for (const char c : algorithm)
    if (!((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '-')) return false;
  return true;
}

std::string system_tcp_congestion() {
  std::ifstream in("/proc/sys/net/ipv4/tcp_congestion_control");
  std::string name;
  in >> name;
  return name;
}

void AcceptedSocketCongestion::apply(int socket_handle) {
  if (algorithm_.empty()) return;
  const std::string problem = set_tcp_congestion(socket_handle, algorithm_);
  if (problem.empty() || refusal_said_) return;
  refusal_said_ = true;
  spdlog::warn("{}: cannot use TCP congestion control \"{}\": {}; connections keep the system's (said once)", who_, algorithm_,
               problem);
}

}  // namespace skinstream::server
