// Runs before main in every skinstream program: the build targets SKINSTREAM_CPU_LEVEL
// (x86-64-v3 by default: AVX2, FMA, BMI2) and would otherwise die of an illegal instruction on an
// older CPU. This file alone is compiled for the baseline x86-64, so it can say why instead.
#include <cstdio>
#include <cstdlib>

namespace {

#define SKINSTREAM_CHECK_LEVEL(level)                                                          \
  if (!__builtin_cpu_supports(level)) {                                                        \
    std::fprintf(stderr,                                                                       \
                 "skinstream: this build needs an " level " CPU and this one is not; rebuild " \
                 "with cmake -DSKINSTREAM_CPU_LEVEL=x86-64\n");                                \
    std::_Exit(1);                                                                             \
  }

// Priority 101: before the constructors of the rest of the program, which may use the level.
__attribute__((constructor(101))) void require_cpu_level() {
  __builtin_cpu_init();
#if defined(SKINSTREAM_CPU_LEVEL_V4)
  SKINSTREAM_CHECK_LEVEL("x86-64-v4")
#elif defined(SKINSTREAM_CPU_LEVEL_V3)
  SKINSTREAM_CHECK_LEVEL("x86-64-v3")
#elif defined(SKINSTREAM_CPU_LEVEL_V2)
  SKINSTREAM_CHECK_LEVEL("x86-64-v2")
#endif
}

}  // namespace
