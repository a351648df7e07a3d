#include "server/cpu_level_check.h"

#include <cstdio>
#include <cstdlib>

namespace skinstream::server {

const char* required_cpu_level() {
#ifdef SKINSTREAM_REQUIRED_CPU_LEVEL
  return SKINSTREAM_REQUIRED_CPU_LEVEL;
#else
  return "";
#endif
}

bool cpu_meets_required_level() {
#ifdef SKINSTREAM_REQUIRED_CPU_LEVEL
  __builtin_cpu_init();
  return __builtin_cpu_supports(SKINSTREAM_REQUIRED_CPU_LEVEL);
#else
  return true;
#endif
}

namespace {

// Priority 101: before the constructors of the rest of the program, which may use the level.
__attribute__((constructor(101))) void exit_unless_cpu_meets_required_level() {
  if (cpu_meets_required_level()) return;
  std::fprintf(stderr,
               "skinstream: this build needs an %s CPU and this one is older; rebuild with "
               "cmake -DSKINSTREAM_CPU_LEVEL=x86-64 (README, \"Two commands\")\n",
               required_cpu_level());
  std::_Exit(1);
}

}  // namespace
}  // namespace skinstream::server
