#pragma once
// A stage network on one machine: a network namespace joined to this host by a veth pair whose
// two ends are each limited by tc's token bucket filter to the same rate (so both directions
// get the link's rate, as a full-duplex Ethernet link does). The daemon runs inside, its
// subscribers outside, and everything they send crosses the shaped link. Only the namespace's
// own /30 is used; the destructor removes the namespace and the veth pair.
// Needs root (CAP_NET_ADMIN) and iproute2 (ip, tc).
#include <string>
#include <vector>

namespace skinstream::bench {

struct ShapedLinkOptions {
  int rate_mbit = 1000;
  int burst_kb = 256;     // tbf's bucket: a few full-size TCP bursts
  int latency_ms = 50;    // tbf's queue: how long a packet may wait before it is dropped
};

class ShapedLink {
 public:
  // Throws std::runtime_error with one line naming what is missing (root, iproute2) or the
  // command that failed and what it printed; anything made before the failure is removed.
  explicit ShapedLink(const ShapedLinkOptions& options);
  ~ShapedLink();
  ShapedLink(const ShapedLink&) = delete;
  ShapedLink& operator=(const ShapedLink&) = delete;

  const std::string& namespace_name() const { return namespace_; }
  const std::string& host_address() const { return host_address_; }    // this side of the link
  const std::string& inner_address() const { return inner_address_; }  // the namespace's side
  // `argv` run inside the namespace: ip netns exec NAME argv...
  std::vector<std::string> inside(const std::vector<std::string>& argv) const;
  // The tc statistics of both ends (bytes sent, packets dropped by the shaper), as JSON text.
  std::string shaper_stats() const;

 private:
  void remove() noexcept;

  std::string namespace_, host_link_, inner_link_, host_address_, inner_address_;
  bool made_ = false;
};

}  // namespace skinstream::bench
