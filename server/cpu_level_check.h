#pragma once
// The CPU check every skinstream program runs before main (linked in as an object, not through
// the server library, so no program can leave it out by not calling it). The build targets
// SKINSTREAM_CPU_LEVEL (x86-64-v3 by default: AVX2, FMA, BMI2), and on an older CPU would die
// of an illegal instruction; cpu_level_check.cpp alone is compiled for the baseline x86-64, so
// it can say why instead and exit 1.

namespace skinstream::server {

// The x86-64 level the build requires ("x86-64-v3"), or "" when it requires none (another
// architecture, or a level that is not an x86-64-vN name).
const char* required_cpu_level();
// Whether this CPU runs the required level (true when there is none).
bool cpu_meets_required_level();

}  // namespace skinstream::server
