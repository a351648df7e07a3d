#pragma once
// Builds a subject file from a range-of-motion take by running `skinstream build-subject` (the
// real-actor fit, build and checks) as a separate process at a low priority (nice 10), so that no
// cost of the build ever lands on the daemon's threads and a build that crashes or hangs takes
// nothing else with it. Its JSON report is kept beside the subject file; on failure the reason
// is the builder's own last line.

#include <atomic>
#include <chrono>
#include <filesystem>
#include <string>

namespace skinstream::server {

struct SubjectBuildRequest {
  std::string builder;                // the skinstream program
  std::filesystem::path capture;      // the take (.c3d)
  std::filesystem::path out;          // the subject file to write
  std::string mesh;                   // --mesh (empty: markers only)
  std::chrono::seconds timeout{600};  // killed after this
};

struct SubjectBuildResult {
  bool ok = false;
  std::string reason;            // when not ok: one line
  double seconds = 0.0;          // wall time of the build
  std::filesystem::path report;  // the builder's JSON report (out + ".json")
};

// Waits for the build (call it off the daemon's frame threads). `cancel` set from another
// thread kills the build.
SubjectBuildResult build_subject(const SubjectBuildRequest& request, const std::atomic<bool>& cancel);

// The skinstream program beside this process's own executable, else "skinstream" (on PATH).
std::string default_subject_builder();

}  // namespace skinstream::server
