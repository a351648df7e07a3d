#include "server/publish/subscriber_network.h"

#include <gtest/gtest.h>

#include "support/ip_address.h"

namespace skinstream::server {
namespace {

using test::ip;

TEST(SubscriberNetwork, RefusesWhatIsNotANetwork) {
  for (const char* bad : {"", "10.0.0.0/", "10.0.0.0/33", "10.0.0.0/-1", "10.0.0.0/8x", "stage", "10.0.0/8", "fd00::/129", "/8"})
    EXPECT_FALSE(SubscriberNetwork::parse(bad)) << bad;
}

TEST(SubscriberNetwork, MatchesIpv4PrefixesOnBitBoundaries) {
  const auto net = *SubscriberNetwork::parse("192.168.16.0/20");
  EXPECT_TRUE(net.contains(ip("192.168.16.1")));
  EXPECT_TRUE(net.contains(ip("192.168.31.255")));
  EXPECT_FALSE(net.contains(ip("192.168.32.0")));
  EXPECT_FALSE(net.contains(ip("192.168.15.255")));
  EXPECT_EQ(net.to_string(), "192.168.16.0/20");
}

TEST(SubscriberNetwork, AnAddressAloneIsOneHost) {
  const auto host = *SubscriberNetwork::parse("10.1.2.3");
  EXPECT_TRUE(host.contains(ip("10.1.2.3")));
  EXPECT_FALSE(host.contains(ip("10.1.2.4")));
  EXPECT_EQ(host.to_string(), "10.1.2.3/32");
  EXPECT_TRUE(SubscriberNetwork::parse("0.0.0.0/0")->contains(ip("203.0.113.9")));
}

TEST(SubscriberNetwork, MatchesIpv6AndIpv4SeenThroughIpv6) {
  const auto ula = *SubscriberNetwork::parse("fd00::/8");
  EXPECT_TRUE(ula.contains(ip("fd12:3456::1")));
  EXPECT_FALSE(ula.contains(ip("fe80::1")));
  EXPECT_FALSE(ula.contains(ip("10.0.0.1")));
  const auto ten = *SubscriberNetwork::parse("10.0.0.0/8");
  EXPECT_TRUE(ten.contains(ip("::ffff:10.9.8.7")));
  EXPECT_FALSE(ten.contains(ip("::ffff:11.0.0.1")));
  EXPECT_FALSE(ten.contains(ip("fd00::1")));
}

// An IPv4 network written as IPv6 (::ffff:a.b.c.d) was taken and never matched, since peers are
// compared as IPv4: it is that IPv4 network; one that splits no IPv4 address (below /96) is refused.
TEST(SubscriberNetwork, Ipv4MappedEntriesAreTheirIpv4Networks) {
  const auto mapped = *SubscriberNetwork::parse("::ffff:10.0.0.0/104");
  EXPECT_EQ(mapped.to_string(), "10.0.0.0/8");
  EXPECT_TRUE(mapped.contains(ip("10.9.8.7")));
  EXPECT_TRUE(mapped.contains(ip("::ffff:10.9.8.7")));
  EXPECT_FALSE(mapped.contains(ip("11.0.0.1")));
  const auto host = *SubscriberNetwork::parse("::ffff:192.168.1.7");
  EXPECT_EQ(host.to_string(), "192.168.1.7/32");
  EXPECT_TRUE(host.contains(ip("192.168.1.7")));
  EXPECT_FALSE(SubscriberNetwork::parse("::ffff:10.0.0.0/64"));
}

}  // namespace
}  // namespace skinstream::server
