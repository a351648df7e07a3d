#pragma once
// Who may subscribe, and how many: decided when a subscriber connects (TCP accept, WebSocket
// upgrade), before any frame is queued for it.
//   - allow-list: the peer's address must be in one of these networks (none listed: any);
//   - at most max_total subscribers in all and max_per_address from one address (0: no limit);
//   - a shared token (empty: none), given in Hello version 2 or on the WebSocket URL.
// With a token, only a subscriber that gave it takes one of those places (admit(), called when
// the token is checked): until then a connection holds one of the few places kept for
// connections without the token (admit_unauthenticated(): max_unauthenticated in all,
// max_unauthenticated_per_address from one address), so idle sockets cannot keep a token holder
// out (4 x 64 of them from four addresses once held all 256 places).
// An admitted subscriber holds a Ticket for its life; its place is free when the ticket goes.
// Any thread (accepts on the io thread, tickets dropped on the publish threads). Made with
// std::make_shared: tickets hold it, as a session may be freed after the daemon's members.

#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

#include "server/asio.h"
#include "server/metrics/metrics.h"
#include "server/publish/subscriber_network.h"

namespace skinstream::server {

struct AdmissionOptions {
  std::vector<SubscriberNetwork> allow;  // empty: every network
  int max_total = 0;                     // 0: no limit
  int max_per_address = 0;               // 0: no limit
  std::string token;                     // empty: none asked
  // With a token: connections that have not given it yet (0: no limit).
  int max_unauthenticated = 64;
  int max_unauthenticated_per_address = 4;
};

class SubscriberAdmission : public std::enable_shared_from_this<SubscriberAdmission> {
 public:
  using Ticket = std::shared_ptr<const void>;
  enum class Refusal { None, NotAllowed, TooMany, TooManyFromAddress, TooManyUnauthenticated };
  struct Decision {
    Ticket ticket;  // null when refused
    Refusal refusal = Refusal::None;
    std::string reason;  // one line, for the peer and the log
  };

  // Refusals are counted in `metrics` (subscribers_refused_not_allowed, _limit, _token).
  SubscriberAdmission(AdmissionOptions options, Metrics& metrics);

  Decision admit(const asio::ip::address& peer);
  // A connection that has yet to give the token (token_required()): one of the places kept for
  // those; its subscriber is admit()ted once the token is right.
  Decision admit_unauthenticated(const asio::ip::address& peer);
  bool token_required() const { return !options_.token.empty(); }
  // Compares in time that depends on the lengths only, not on where the bytes first differ. A
  // mismatch is a refusal, counted (subscribers_refused_token) for the whole daemon.
  bool token_matches(std::string_view given) const;

  const AdmissionOptions& options() const { return options_; }
  int admitted() const;
  int unauthenticated() const;

 private:
  // The places of one kind: subscribers, or connections without the token yet.
  struct Places {
    int total = 0;
    std::map<asio::ip::address, int> per_address;
  };
  bool allowed(const asio::ip::address& peer, Decision& out_decision) const;
  Refusal take(Places& places, const asio::ip::address& peer, int max_total, int max_per_address, Ticket& out_ticket);
  void release(Places& places, const asio::ip::address& peer);

  AdmissionOptions options_;
  Metrics& metrics_;
  mutable std::mutex mutex_;
  Places admitted_, unauthenticated_;
};

}  // namespace skinstream::server
