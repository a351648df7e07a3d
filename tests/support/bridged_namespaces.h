#pragma once
// A LAN on one machine, for what needs more than loopback (multicast does not loop back here):
// a bridge in a network namespace of its own and `hosts` namespaces, each joined to it by a veth
// pair, host i at 10.215.0.(i + 1)/24. Everything lives in the namespaces this object made (named
// after the process id), so the addresses touch nothing else, and the destructor removes them,
// with the veth pairs and the bridge inside. Needs root and iproute2.
#include <string>
#include <vector>

namespace skinstream::test {

class BridgedNamespaces {
 public:
  // Why they cannot be made here (not root, no `ip`), in one line; empty when they can.
  static std::string unavailable_reason();
  // Throws std::runtime_error naming the command that failed and what it printed; anything made
  // before is removed.
  explicit BridgedNamespaces(int hosts);
  ~BridgedNamespaces();
  BridgedNamespaces(const BridgedNamespaces&) = delete;
  BridgedNamespaces& operator=(const BridgedNamespaces&) = delete;

  int hosts() const { return static_cast<int>(hosts_.size()); }
  const std::string& name(int host) const { return hosts_[host]; }
  std::string address(int host) const { return "10.215.0." + std::to_string(host + 1); }
  // A shell command's prefix that runs it in host's namespace.
  std::string exec_prefix(int host) const { return "ip netns exec " + hosts_[host]; }
  // Moves the calling thread into host's network namespace for the rest of its life (sockets it
  // opens then belong there). Throws std::runtime_error when it cannot.
  void enter(int host) const;
  // Runs a shell command in host's namespace; throws std::runtime_error when it fails.
  std::string run_in(int host, const std::string& command) const;

 private:
  void remove() noexcept;
  std::string bridge_;
  std::vector<std::string> hosts_;
};

}  // namespace skinstream::test
