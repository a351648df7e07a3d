#pragma once
// Puts the multicast offer (docs/subscriber-protocol.md, "The offer") back together: the packed
// MeshInfo and Model a joining receiver needs, which the daemon sends round and round to the
// group's offer port. The offer repeats, so a receiver that joins halfway through a round, or
// loses datagrams, takes the fragments it lacks from the next round: nothing is asked for again.
//
// One offer is put together at a time, identified by its edition (the header's sequence), model
// id, fragment count and size. A datagram of another offer starts that one afresh only when the
// one in progress has had no datagram for `stale_after` (the daemon moved on to a new edition):
// a forger's datagrams cannot make the receiver drop a nearly complete offer for each of theirs.
// Without a key, a forger can still spoil the offer; the receiver then waits out its own limit
// and fetches over TCP (client::MulticastOptions::offer_wait). With a key only signed datagrams
// are taken.
//
// The buffer grows to the offer's size once (at most kMaxOfferFragments fragments, 5.6 MB), as
// the first datagram of an offer arrives; the rest of the work allocates nothing.

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "protocol/subscriber/datagram_authentication.h"
#include "protocol/subscriber/multicast_datagram.h"

namespace skinstream::subscriber {

class OfferReassembler {
 public:
  using Clock = std::chrono::steady_clock;
  struct Options {
    uint32_t stream_id = 0;  // datagrams of other streams are counted and ignored
    std::chrono::nanoseconds stale_after = std::chrono::milliseconds(500);
    std::shared_ptr<const DatagramAuthenticator> authenticator{};  // set: datagrams must carry its tag
  };
  struct Stats {
    uint64_t datagrams = 0;           // taken, of this stream
    uint64_t datagrams_rejected = 0;  // broke the protocol, were no offer's, or lacked the key's tag
    uint64_t datagrams_other_stream = 0;
    uint64_t datagrams_duplicate = 0;    // a fragment already held (the next round)
    uint64_t datagrams_other_offer = 0;  // of another offer while one was in progress
    uint64_t offers_begun = 0;
    uint64_t offers_completed = 0;
  };
  struct Offer {
    std::span<const unsigned char> bytes;  // the offer: valid until the next add() or restart()
    DatagramHeader header;                 // of its last fragment (edition, model id)
  };

  explicit OfferReassembler(const Options& options);

  // Takes one datagram (arrived at `now`). Returns the offer it completes, if it does. Throws
  // DecodeError for a datagram that breaks the protocol, is not of the offer, or lacks the key's
  // tag (counted in datagrams_rejected); the offer in progress is kept.
  std::optional<Offer> add(std::span<const unsigned char> datagram, Clock::time_point now);
  // Forgets the offer in progress (or the one completed): the next datagram starts one afresh.
  // For a completed offer whose content the receiver refused.
  void restart();
  const Stats& stats() const { return stats_; }

 private:
  Options options_;
  bool in_progress_ = false;
  DatagramHeader offer_;            // edition, model id, count and size of the offer in progress
  std::vector<uint64_t> received_;  // bit i: fragment i arrived
  uint32_t fragments_ = 0;
  Clock::time_point last_arrival_{};  // of a datagram of the offer in progress
  std::vector<unsigned char> bytes_;
  Stats stats_;
};

}  // namespace skinstream::subscriber
