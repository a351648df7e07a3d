#include "server/pipeline/deform_cpus.h"

#include <pthread.h>
#include <sched.h>

#include <algorithm>
#include <stdexcept>

namespace skinstream::server {
namespace {

// Parses "3,1,2" into numbers; `ok` false for anything else.
std::vector<int> parse_list(const std::string& spec, bool& ok) {
  std::vector<int> cpus;
  ok = !spec.empty();
  size_t at = 0;
  while (ok && at <= spec.size()) {
    const size_t comma = std::min(spec.find(',', at), spec.size());
    const std::string item = spec.substr(at, comma - at);
    ok = !item.empty() && item.size() <= 4 && item.find_first_not_of("0123456789") == std::string::npos;
    if (ok) cpus.push_back(std::stoi(item));
    at = comma + 1;
  }
  return cpus;
}

bool set_cpus(pthread_t thread, const std::vector<int>& cpus) {
  cpu_set_t set;
  CPU_ZERO(&set);
  for (int cpu : cpus) {
    if (cpu < 0 || cpu >= CPU_SETSIZE) return false;
    CPU_SET(cpu, &set);
  }
  return !cpus.empty() && pthread_setaffinity_np(thread, sizeof(set), &set) == 0;
}

}  // namespace

std::string deform_cpus_problem(const std::string& spec) {
  if (spec == "auto" || spec == "off") return {};
  bool ok = false;
  const std::vector<int> cpus = parse_list(spec, ok);
  if (!ok) return "deform_cpus must be \"auto\", \"off\" or CPU numbers separated by commas (\"2,3\"), not \"" + spec + "\"";
  std::vector<int> sorted = cpus;
  std::sort(sorted.begin(), sorted.end());
  if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end()) return "deform_cpus names a CPU twice: \"" + spec + "\"";
  return {};
}

std::vector<int> choose_deform_cpus(const std::string& spec, int threads, const std::vector<int>& allowed) {
  if (const std::string problem = deform_cpus_problem(spec); !problem.empty()) throw std::invalid_argument(problem);
  if (spec == "off") return {};
  if (spec == "auto") {
    if (threads < 1 || static_cast<int>(allowed.size()) < threads) return {};
    return {allowed.end() - threads, allowed.end()};
  }
  bool ok = false;
  const std::vector<int> cpus = parse_list(spec, ok);
  if (static_cast<int>(cpus.size()) != threads)
    throw std::invalid_argument("deform_cpus names " + std::to_string(cpus.size()) + " CPUs for " + std::to_string(threads) +
                                " deform threads (one each, the pipeline thread first)");
  for (int cpu : cpus)
    if (!std::binary_search(allowed.begin(), allowed.end(), cpu))
      throw std::invalid_argument("deform_cpus: CPU " + std::to_string(cpu) + " is not one this process may run on");
  return cpus;
}

std::vector<int> allowed_cpus() {
  cpu_set_t set;
  CPU_ZERO(&set);
  std::vector<int> cpus;
  if (sched_getaffinity(0, sizeof(set), &set) != 0) return cpus;
  for (int cpu = 0; cpu < CPU_SETSIZE; ++cpu)
    if (CPU_ISSET(cpu, &set)) cpus.push_back(cpu);
  return cpus;
}

bool set_thread_cpus(std::thread& thread, const std::vector<int>& cpus) { return set_cpus(thread.native_handle(), cpus); }
bool set_this_thread_cpus(const std::vector<int>& cpus) { return set_cpus(pthread_self(), cpus); }

}  // namespace skinstream::server
