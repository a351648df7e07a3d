#include "server/publish/subscriber_network.h"

#include <charconv>

namespace skinstream::server {
namespace {

// The first `bits` bits of a and b agree.
bool same_prefix(const unsigned char* a, const unsigned char* b, int bits) {
  const int whole = bits / 8;
  for (int i = 0; i < whole; ++i)
    if (a[i] != b[i]) return false;
  const int rest = bits % 8;
  if (rest == 0) return true;
  const auto mask = static_cast<unsigned char>(0xFF << (8 - rest));
  return (a[whole] & mask) == (b[whole] & mask);
}

}  // namespace

std::optional<SubscriberNetwork> SubscriberNetwork::parse(std::string_view text) {
  const size_t slash = text.find('/');
  boost::system::error_code ec;
  const asio::ip::address address = asio::ip::make_address(std::string(text.substr(0, slash)), ec);
  if (ec) return std::nullopt;
  SubscriberNetwork network;
  network.v6_ = address.is_v6();
  const int max_bits = network.v6_ ? 128 : 32;
  network.prefix_bits_ = max_bits;
  if (slash != std::string_view::npos) {
    const std::string_view digits = text.substr(slash + 1);
    const auto [end, error] = std::from_chars(digits.data(), digits.data() + digits.size(), network.prefix_bits_);
    if (digits.empty() || error != std::errc() || end != digits.data() + digits.size()) return std::nullopt;
    if (network.prefix_bits_ < 0 || network.prefix_bits_ > max_bits) return std::nullopt;
  }
  if (network.v6_ && address.to_v6().is_v4_mapped()) {
    // An IPv4 network written as IPv6: what the peers it means are compared as.
    if (network.prefix_bits_ < 96) return std::nullopt;
    network.v6_ = false;
    network.prefix_bits_ -= 96;
    const auto v4 = asio::ip::make_address_v4(asio::ip::v4_mapped, address.to_v6()).to_bytes();
    std::copy(v4.begin(), v4.end(), network.bytes_.begin());
  } else if (network.v6_) {
    network.bytes_ = address.to_v6().to_bytes();
  } else {
    const auto v4 = address.to_v4().to_bytes();
    std::copy(v4.begin(), v4.end(), network.bytes_.begin());
  }
  return network;
}

bool SubscriberNetwork::contains(const asio::ip::address& in) const {
  asio::ip::address address = in;
  if (address.is_v6() && address.to_v6().is_v4_mapped()) address = asio::ip::make_address_v4(asio::ip::v4_mapped, address.to_v6());
  if (address.is_v6() != v6_) return false;
  if (v6_) return same_prefix(address.to_v6().to_bytes().data(), bytes_.data(), prefix_bits_);
  return same_prefix(address.to_v4().to_bytes().data(), bytes_.data(), prefix_bits_);
}

std::string SubscriberNetwork::to_string() const {
  asio::ip::address address;
  if (v6_) {
    address = asio::ip::address_v6(bytes_);
  } else {
    address = asio::ip::address_v4(asio::ip::address_v4::bytes_type{bytes_[0], bytes_[1], bytes_[2], bytes_[3]});
  }
  return address.to_string() + "/" + std::to_string(prefix_bits_);
}

}  // namespace skinstream::server
