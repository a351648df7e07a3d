#pragma once
// Names the daemon gives what it writes (takes, calibrations): UTC times as text, and a subject's
// name made safe for a file name.

#include <chrono>
#include <string>

namespace skinstream::server {

// `when` in UTC by strftime's `format` ("%Y%m%d-%H%M%S").
std::string utc_text(std::chrono::system_clock::time_point when, const char* format);
// `when` as ISO 8601 UTC: "2026-12-06T08:32:03Z".
std::string iso_utc(std::chrono::system_clock::time_point when);
// Letters, digits, '-', '_' and '.' kept, anything else '_', at most 64 bytes, never hidden (a
// leading '.' gets an 's'): "Actor 1/a" -> "Actor_1_a".
std::string file_stem_of(const std::string& name);

}  // namespace skinstream::server
