#include "support/bridged_namespaces.h"

#include <fcntl.h>
#include <sched.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "server/client/stale_namespaces.h"
#include "support/program_run.h"

namespace skinstream::test {
namespace {

std::string must(const std::string& command) {
  const ProgramRun run = run_program(command);
  if (run.exit_code != 0) {
    std::string output = run.output;
    for (char& c : output)
      if (c == '\n') c = ' ';
    throw std::runtime_error("\"" + command + "\" failed: " + output);
  }
  return run.output;
}

}  // namespace

std::string BridgedNamespaces::unavailable_reason() {
  if (geteuid() != 0) return "needs root to make network namespaces, a bridge and veth pairs";
  if (run_program("ip -V").exit_code != 0) return "needs iproute2's ip (Debian: apt-get install iproute2)";
  return "";
}

BridgedNamespaces::BridgedNamespaces(int hosts) {
  // What a run killed before its destructor left (named after its process, now gone).
  for (const std::string& left_over : server::namespaces_of_dead_processes("skmc")) run_program("ip netns del " + left_over);
  const std::string stem = "skmc" + std::to_string(getpid());
  try {
    bridge_ = stem + "-lan";
    must("ip netns add " + bridge_);
    // No IGMP snooping: the bridge floods the group to every port, as an unmanaged switch does.
    must("ip -n " + bridge_ + " link add lan type bridge mcast_snooping 0");
    must("ip -n " + bridge_ + " link set lan up");
    for (int i = 0; i < hosts; ++i) {
      hosts_.push_back(stem + "-h" + std::to_string(i));
      const std::string& host = hosts_.back();
      const std::string port = "port" + std::to_string(i);
      must("ip netns add " + host);
      must("ip link add " + port + " netns " + bridge_ + " type veth peer name eth0 netns " + host);
      must("ip -n " + bridge_ + " link set " + port + " master lan up");
      must("ip -n " + host + " addr add " + address(i) + "/24 dev eth0");
      must("ip -n " + host + " link set eth0 up");
      must("ip -n " + host + " link set lo up");
    }
  } catch (...) {
    remove();
    throw;
  }
}

BridgedNamespaces::~BridgedNamespaces() { remove(); }

void BridgedNamespaces::remove() noexcept {
  // A namespace takes its end of each veth pair, and so the pair, and the bridge with it.
  for (const std::string& host : hosts_) run_program("ip netns del " + host);
  if (!bridge_.empty()) run_program("ip netns del " + bridge_);
  hosts_.clear();
  bridge_.clear();
}

void BridgedNamespaces::enter(int host) const {
  const std::string path = "/var/run/netns/" + hosts_[host];
  const int fd = open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw std::runtime_error(path + ": " + std::strerror(errno));
  const int rc = setns(fd, CLONE_NEWNET);
  const int error = errno;
  close(fd);
  if (rc != 0) throw std::runtime_error("setns " + path + ": " + std::strerror(error));
}

std::string BridgedNamespaces::run_in(int host, const std::string& command) const { return must(exec_prefix(host) + " " + command); }

}  // namespace skinstream::test
