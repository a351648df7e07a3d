#pragma once
// One network of the subscriber allow-list: "10.0.0.0/8", "192.168.1.7" (a /32),
// "fd00::/8", "::1" (a /128). An IPv4 peer seen through an IPv6 socket (::ffff:10.1.2.3)
// matches the IPv4 networks, as it is the same peer; and an entry written that way
// ("::ffff:10.0.0.0/104", "::ffff:192.168.1.7") is that IPv4 network (10.0.0.0/8, a /32): it was
// taken and never matched. One that does not cover whole IPv4 addresses (a prefix below 96) is
// refused.

#include <array>
#include <optional>
#include <string>
#include <string_view>

#include "server/asio.h"

namespace skinstream::server {

class SubscriberNetwork {
 public:
  // nullopt for anything but an address with an optional prefix length in range.
  static std::optional<SubscriberNetwork> parse(std::string_view text);
  bool contains(const asio::ip::address& address) const;
  std::string to_string() const;

 private:
  bool v6_ = false;
  std::array<unsigned char, 16> bytes_{};  // the first 4 for IPv4
  int prefix_bits_ = 0;
};

}  // namespace skinstream::server
