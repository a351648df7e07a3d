#include "server/publish/subscriber_admission.h"

#include <gtest/gtest.h>

#include "support/ip_address.h"

namespace skinstream::server {
namespace {

using test::ip;

TEST(SubscriberAdmission, RefusesAddressesOutsideTheAllowList) {
  Metrics metrics;
  AdmissionOptions options;
  options.allow = {*SubscriberNetwork::parse("10.0.0.0/8")};
  auto admission = std::make_shared<SubscriberAdmission>(options, metrics);
  const auto outside = admission->admit(ip("192.168.1.2"));
  EXPECT_EQ(outside.refusal, SubscriberAdmission::Refusal::NotAllowed);
  EXPECT_FALSE(outside.ticket);
  EXPECT_EQ(outside.reason, "address 192.168.1.2 is not in this daemon's allow_subscribers networks");
  EXPECT_TRUE(admission->admit(ip("::ffff:10.0.0.5")).ticket);
  EXPECT_EQ(metrics.subscribers_refused_not_allowed.load(), 1u);
}

TEST(SubscriberAdmission, CountsPlacesInAllAndPerAddressUntilTicketsGo) {
  Metrics metrics;
  auto admission = std::make_shared<SubscriberAdmission>(AdmissionOptions{{}, 3, 2, ""}, metrics);
  auto a = admission->admit(ip("10.0.0.1")), b = admission->admit(ip("::ffff:10.0.0.1"));
  ASSERT_TRUE(a.ticket && b.ticket);
  EXPECT_EQ(admission->admit(ip("10.0.0.1")).refusal, SubscriberAdmission::Refusal::TooManyFromAddress);
  auto c = admission->admit(ip("10.0.0.2"));
  ASSERT_TRUE(c.ticket);
  EXPECT_EQ(admission->admit(ip("10.0.0.3")).refusal, SubscriberAdmission::Refusal::TooMany);
  EXPECT_EQ(admission->admitted(), 3);
  a.ticket.reset();
  EXPECT_EQ(admission->admitted(), 2);
  EXPECT_TRUE(admission->admit(ip("10.0.0.1")).ticket);
  EXPECT_EQ(metrics.subscribers_refused_limit.load(), 2u);
}

// Connections without the token have places of their own: they take none of the subscribers'.
TEST(SubscriberAdmission, ConnectionsWithoutTheTokenHaveTheirOwnFewPlaces) {
  Metrics metrics;
  AdmissionOptions options{{}, 2, 2, "secret"};
  options.max_unauthenticated = 3;
  options.max_unauthenticated_per_address = 2;
  auto admission = std::make_shared<SubscriberAdmission>(options, metrics);
  auto a = admission->admit_unauthenticated(ip("10.0.0.1")), b = admission->admit_unauthenticated(ip("10.0.0.1"));
  ASSERT_TRUE(a.ticket && b.ticket);
  const auto third = admission->admit_unauthenticated(ip("::ffff:10.0.0.1"));
  EXPECT_EQ(third.refusal, SubscriberAdmission::Refusal::TooManyUnauthenticated);
  EXPECT_EQ(third.reason, "too many connections without the token from 10.0.0.1: at most 2 from one address (max_unauthenticated_per_address)");
  auto c = admission->admit_unauthenticated(ip("10.0.0.2"));
  ASSERT_TRUE(c.ticket);
  EXPECT_EQ(admission->admit_unauthenticated(ip("10.0.0.3")).reason,
            "too many connections without the token: at most 3 at once (max_unauthenticated_subscribers)");
  EXPECT_EQ(admission->unauthenticated(), 3);
  // The subscribers' places are all still free.
  auto subscriber = admission->admit(ip("10.0.0.1"));
  ASSERT_TRUE(subscriber.ticket);
  EXPECT_EQ(admission->admitted(), 1);
  a.ticket.reset();  // it gave the token: its place without it goes
  EXPECT_EQ(admission->unauthenticated(), 2);
  EXPECT_EQ(metrics.subscribers_refused_unauthenticated.load(), 2u);
  EXPECT_EQ(metrics.subscribers_refused_limit.load(), 0u);
}

TEST(SubscriberAdmission, TicketsOutliveTheAdmission) {
  Metrics metrics;
  SubscriberAdmission::Ticket ticket;
  {
    auto admission = std::make_shared<SubscriberAdmission>(AdmissionOptions{{}, 1, 1, ""}, metrics);
    ticket = admission->admit(ip("10.0.0.1")).ticket;
  }
  ticket.reset();  // released into the admission it kept alive
}

TEST(SubscriberAdmission, MatchesTheTokenExactly) {
  Metrics metrics;
  auto none = std::make_shared<SubscriberAdmission>(AdmissionOptions{}, metrics);
  EXPECT_FALSE(none->token_required());
  auto admission = std::make_shared<SubscriberAdmission>(AdmissionOptions{{}, 0, 0, "stage-7"}, metrics);
  EXPECT_TRUE(admission->token_required());
  EXPECT_TRUE(admission->token_matches("stage-7"));
  for (const char* wrong : {"", "stage-", "stage-77", "Stage-7", "stage-8"}) EXPECT_FALSE(admission->token_matches(wrong)) << wrong;
  EXPECT_FALSE(admission->token_matches(std::string_view("stage-7\0", 8)));
}

}  // namespace
}  // namespace skinstream::server
