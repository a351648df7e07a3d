#include "clients/bench/shaped_link.h"

#include <unistd.h>

#include <stdexcept>

#include "clients/bench/child_command.h"
#include "server/client/stale_namespaces.h"

namespace skinstream::bench {
namespace {

std::string joined(const std::vector<std::string>& argv) {
  std::string text;
  for (const std::string& a : argv) text += (text.empty() ? "" : " ") + a;
  return text;
}

std::string one_line(std::string text) {
  for (char& c : text)
    if (c == '\n' || c == '\r') c = ' ';
  while (!text.empty() && text.back() == ' ') text.pop_back();
  return text;
}

void must(const std::vector<std::string>& argv) {
  const CommandResult result = run_command(argv);
  if (result.exit_code != 0) throw std::runtime_error("\"" + joined(argv) + "\" failed: " + one_line(result.output));
}

}  // namespace

ShapedLink::ShapedLink(const ShapedLinkOptions& options) {
  if (geteuid() != 0)
    throw std::runtime_error("--link-mbit needs root (CAP_NET_ADMIN) to make a network namespace and shape it with tc; run as root or leave --link-mbit out");
  if (run_command({"ip", "-V"}).exit_code != 0 || run_command({"tc", "-V"}).exit_code != 0)
    throw std::runtime_error("--link-mbit needs iproute2's ip and tc (Debian: apt-get install iproute2)");
  if (options.rate_mbit < 1) throw std::runtime_error("--link-mbit must be at least 1");
  // What a bench killed before its destructor left (named after its process, now gone): the
  // namespace takes its veth pair with it.
  for (const std::string& left_over : server::namespaces_of_dead_processes("skbench"))
    run_command({"ip", "netns", "del", left_over});
  // Names and a /30 of 10.213.0.0/16 from the process id: two benches at once do not collide.
  const unsigned id = static_cast<unsigned>(getpid()) & 0x3fff;
  namespace_ = "skbench" + std::to_string(getpid());
  host_link_ = "skbh" + std::to_string(id);
  inner_link_ = "skbn" + std::to_string(id);
  const std::string prefix = "10.213." + std::to_string(id >> 6) + ".";
  host_address_ = prefix + std::to_string((id & 63) * 4 + 1);
  inner_address_ = prefix + std::to_string((id & 63) * 4 + 2);
  const std::string rate = std::to_string(options.rate_mbit) + "mbit", burst = std::to_string(options.burst_kb) + "kb",
                    latency = std::to_string(options.latency_ms) + "ms";
  try {
    must({"ip", "netns", "add", namespace_});
    made_ = true;
    must({"ip", "link", "add", host_link_, "type", "veth", "peer", "name", inner_link_});
    must({"ip", "link", "set", inner_link_, "netns", namespace_});
    must({"ip", "addr", "add", host_address_ + "/30", "dev", host_link_});
    must({"ip", "link", "set", host_link_, "up"});
    must(inside({"ip", "addr", "add", inner_address_ + "/30", "dev", inner_link_}));
    must(inside({"ip", "link", "set", inner_link_, "up"}));
    must(inside({"ip", "link", "set", "lo", "up"}));
    must({"tc", "qdisc", "add", "dev", host_link_, "root", "tbf", "rate", rate, "burst", burst, "latency", latency});
    must(inside({"tc", "qdisc", "add", "dev", inner_link_, "root", "tbf", "rate", rate, "burst", burst, "latency", latency}));
  } catch (...) {
    remove();
    throw;
  }
}

ShapedLink::~ShapedLink() { remove(); }

void ShapedLink::remove() noexcept {
  if (!made_) return;
  made_ = false;
  try {
    run_command(
        {"ip", "netns", "del", namespace_});  // takes its end of the veth pair, and so the pair, with it
    run_command(
        {"ip", "link", "del", host_link_});  // in case the pair outlived it; fails harmlessly otherwise
  } catch (...) {
  }
}

std::vector<std::string> ShapedLink::inside(const std::vector<std::string>& argv) const {
  std::vector<std::string> wrapped = {"ip", "netns", "exec", namespace_};
  wrapped.insert(wrapped.end(), argv.begin(), argv.end());
  return wrapped;
}

std::string ShapedLink::shaper_stats() const {
  const CommandResult host = run_command({"tc", "-s", "-j", "qdisc", "show", "dev", host_link_});
  const CommandResult inner = run_command(inside({"tc", "-s", "-j", "qdisc", "show", "dev", inner_link_}));
  return "{\"to_namespace\":" + (host.exit_code == 0 ? one_line(host.output) : "null") +
         ",\"from_namespace\":" + (inner.exit_code == 0 ? one_line(inner.output) : "null") + "}";
}

}  // namespace skinstream::bench
