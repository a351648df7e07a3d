#pragma once
// Who may subscribe, and how many: decided when a subscriber connects (TCP accept, WebSocket
// upgrade), before any frame is queued for it.
//   - allow-list: the peer's address must be in one of these networks (none listed: any);
//   - at most max_total subscribers in all and max_per_address from one address (0: no limit);
//   - a shared token (empty: none), given in Hello version 2 or on the WebSocket URL.
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
};

class SubscriberAdmission : public std::enable_shared_from_this<SubscriberAdmission> {
 public:
  using Ticket = std::shared_ptr<const void>;
  enum class Refusal { None, NotAllowed, TooMany, TooManyFromAddress };
  struct Decision {
    Ticket ticket;  // null when refused
    Refusal refusal = Refusal::None;
    std::string reason;  // one line, for the peer and the log
  };

  // Refusals are counted in `metrics` (subscribers_refused_not_allowed, _limit, _token).
  SubscriberAdmission(AdmissionOptions options, Metrics& metrics);

  Decision admit(const asio::ip::address& peer);
  bool token_required() const { return !options_.token.empty(); }
  // Compares in time that depends on the lengths only, not on where the bytes first differ. A
  // mismatch is a refusal, counted (subscribers_refused_token) for the whole daemon.
  bool token_matches(std::string_view given) const;

  const AdmissionOptions& options() const { return options_; }
  int admitted() const;

 private:
  void release(const asio::ip::address& peer);

  AdmissionOptions options_;
  Metrics& metrics_;
  mutable std::mutex mutex_;
  int admitted_ = 0;
  std::map<asio::ip::address, int> per_address_;
};

}  // namespace skinstream::server
