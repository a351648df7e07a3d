#include "server/publish/subscriber_admission.h"

#include <algorithm>

namespace skinstream::server {
namespace {

// An IPv4 peer seen through an IPv6 socket is the same peer as over IPv4.
asio::ip::address plain(const asio::ip::address& address) {
  if (address.is_v6() && address.to_v6().is_v4_mapped()) return asio::ip::make_address_v4(asio::ip::v4_mapped, address.to_v6());
  return address;
}

}  // namespace

SubscriberAdmission::SubscriberAdmission(AdmissionOptions options, Metrics& metrics) : options_(std::move(options)), metrics_(metrics) {}

SubscriberAdmission::Decision SubscriberAdmission::admit(const asio::ip::address& in) {
  const asio::ip::address peer = plain(in);
  Decision decision;
  if (!options_.allow.empty()) {
    bool allowed = false;
    for (const SubscriberNetwork& network : options_.allow) allowed = allowed || network.contains(peer);
    if (!allowed) {
      metrics_.subscribers_refused_not_allowed.fetch_add(1, std::memory_order_relaxed);
      decision.refusal = Refusal::NotAllowed;
      decision.reason = "address " + peer.to_string() + " is not in this daemon's allow_subscribers networks";
      return decision;
    }
  }
  std::lock_guard lock(mutex_);
  int& from_peer = per_address_[peer];
  if (options_.max_total > 0 && admitted_ >= options_.max_total) {
    decision.refusal = Refusal::TooMany;
    decision.reason = "too many subscribers: this daemon serves at most " + std::to_string(options_.max_total) + " (max_subscribers)";
  } else if (options_.max_per_address > 0 && from_peer >= options_.max_per_address) {
    decision.refusal = Refusal::TooManyFromAddress;
    decision.reason = "too many subscribers from " + peer.to_string() + ": at most " + std::to_string(options_.max_per_address) +
                      " from one address (max_subscribers_per_address)";
  }
  if (decision.refusal != Refusal::None) {
    if (from_peer == 0) per_address_.erase(peer);
    metrics_.subscribers_refused_limit.fetch_add(1, std::memory_order_relaxed);
    return decision;
  }
  ++admitted_;
  ++from_peer;
  decision.ticket = std::shared_ptr<const void>(this, [self = shared_from_this(), peer](const void*) { self->release(peer); });
  return decision;
}

void SubscriberAdmission::release(const asio::ip::address& peer) {
  std::lock_guard lock(mutex_);
  --admitted_;
  const auto it = per_address_.find(peer);
  if (it != per_address_.end() && --it->second <= 0) per_address_.erase(it);
}

bool SubscriberAdmission::token_matches(std::string_view given) const {
  const std::string& expected = options_.token;
  // Every byte of the longer string is looked at whatever the others hold.
  const size_t n = std::max(expected.size(), given.size());
  unsigned char difference = expected.size() == given.size() ? 0 : 1;
  for (size_t i = 0; i < n; ++i) {
    const unsigned char a = i < expected.size() ? static_cast<unsigned char>(expected[i]) : 0;
    const unsigned char b = i < given.size() ? static_cast<unsigned char>(given[i]) : 0;
    difference |= static_cast<unsigned char>(a ^ b);
  }
  const bool matches = difference == 0 && !expected.empty();
  if (!matches) metrics_.subscribers_refused_token.fetch_add(1, std::memory_order_relaxed);
  return matches;
}

int SubscriberAdmission::admitted() const {
  std::lock_guard lock(mutex_);
  return admitted_;
}

}  // namespace skinstream::server
