#include "server/publish/subscriber_admission.h"

#include "server/constant_time_equal.h"

namespace skinstream::server {
namespace {

// An IPv4 peer seen through an IPv6 socket is the same peer as over IPv4.
asio::ip::address plain(const asio::ip::address& address) {
  if (address.is_v6() && address.to_v6().is_v4_mapped()) return asio::ip::make_address_v4(asio::ip::v4_mapped, address.to_v6());
  return address;
}

}  // namespace

SubscriberAdmission::SubscriberAdmission(AdmissionOptions options, Metrics& metrics) : options_(std::move(options)), metrics_(metrics) {}

bool SubscriberAdmission::allowed(const asio::ip::address& peer, Decision& out_decision) const {
  if (options_.allow.empty()) return true;
  for (const SubscriberNetwork& network : options_.allow)
    if (network.contains(peer)) return true;
  metrics_.subscribers_refused_not_allowed.fetch_add(1, std::memory_order_relaxed);
  out_decision.refusal = Refusal::NotAllowed;
  out_decision.reason = "address " + peer.to_string() + " is not in this daemon's allow_subscribers networks";
  return false;
}

SubscriberAdmission::Decision SubscriberAdmission::admit(const asio::ip::address& in) {
  const asio::ip::address peer = plain(in);
  Decision decision;
  if (!allowed(peer, decision)) return decision;
  std::lock_guard lock(mutex_);
  decision.refusal = take(admitted_, peer, options_.max_total, options_.max_per_address, decision.ticket);
  if (decision.refusal == Refusal::None) return decision;
  decision.reason = decision.refusal == Refusal::TooMany
                        ? "too many subscribers: this daemon serves at most " + std::to_string(options_.max_total) + " (max_subscribers)"
                        : "too many subscribers from " + peer.to_string() + ": at most " + std::to_string(options_.max_per_address) +
                              " from one address (max_subscribers_per_address)";
  metrics_.subscribers_refused_limit.fetch_add(1, std::memory_order_relaxed);
  return decision;
}

SubscriberAdmission::Decision SubscriberAdmission::admit_unauthenticated(const asio::ip::address& in) {
  const asio::ip::address peer = plain(in);
  Decision decision;
  if (!allowed(peer, decision)) return decision;
  std::lock_guard lock(mutex_);
  const Refusal refusal =
      take(unauthenticated_, peer, options_.max_unauthenticated, options_.max_unauthenticated_per_address, decision.ticket);
  if (refusal == Refusal::None) return decision;
  decision.refusal = Refusal::TooManyUnauthenticated;
  decision.reason = refusal == Refusal::TooMany
                        ? "too many connections without the token: at most " + std::to_string(options_.max_unauthenticated) +
                              " at once (max_unauthenticated_subscribers)"
                        : "too many connections without the token from " + peer.to_string() + ": at most " +
                              std::to_string(options_.max_unauthenticated_per_address) +
                              " from one address (max_unauthenticated_per_address)";
  metrics_.subscribers_refused_unauthenticated.fetch_add(1, std::memory_order_relaxed);
  return decision;
}

// With the mutex held: a place of `places` for `peer` (its ticket in out_ticket), or the limit
// that refused it (TooMany, TooManyFromAddress).
SubscriberAdmission::Refusal SubscriberAdmission::take(Places& places, const asio::ip::address& peer, int max_total,
                                                       int max_per_address, Ticket& out_ticket) {
  int& from_peer = places.per_address[peer];
  Refusal refusal = Refusal::None;
  if (max_total > 0 && places.total >= max_total) refusal = Refusal::TooMany;
  else if (max_per_address > 0 && from_peer >= max_per_address) refusal = Refusal::TooManyFromAddress;
  if (refusal != Refusal::None) {
    if (from_peer == 0) places.per_address.erase(peer);
    return refusal;
  }
  ++places.total;
  ++from_peer;
  out_ticket = std::shared_ptr<const void>(this, [self = shared_from_this(), &places, peer](const void*) { self->release(places, peer); });
  return Refusal::None;
}

void SubscriberAdmission::release(Places& places, const asio::ip::address& peer) {
  std::lock_guard lock(mutex_);
  --places.total;
  const auto it = places.per_address.find(peer);
  if (it != places.per_address.end() && --it->second <= 0) places.per_address.erase(it);
}

bool SubscriberAdmission::token_matches(std::string_view given) const {
  const bool matches = constant_time_equal(given, options_.token) && !options_.token.empty();
  if (!matches) metrics_.subscribers_refused_token.fetch_add(1, std::memory_order_relaxed);
  return matches;
}

int SubscriberAdmission::admitted() const {
  std::lock_guard lock(mutex_);
  return admitted_.total;
}

int SubscriberAdmission::unauthenticated() const {
  std::lock_guard lock(mutex_);
  return unauthenticated_.total;
}

}  // namespace skinstream::server
