#include "clients/skinstream/default_paths.h"

#include <cstdlib>
#include <filesystem>
#include <vector>

namespace skinstream::cli {

std::string default_body_dir() {
  namespace fs = std::filesystem;
  if (const char* d = std::getenv("SKINSTREAM_MAKEHUMAN_DIR")) return d;
  if (const char* d = std::getenv("SKINSTREAM_SHARED_DIR")) return std::string(d) + "/data/meshes/makehuman";
  std::vector<fs::path> tries;
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec)  // build/bin/skinstream -> <root>/../shared
    for (fs::path p = exe.parent_path(); !p.empty() && p != p.root_path(); p = p.parent_path()) {
      tries.push_back(p / "shared" / "data" / "meshes" / "makehuman");
      tries.push_back(p / "replay_data" / "makehuman");  // the copy bundled with the project
    }
  tries.push_back(fs::current_path(ec) / ".." / "shared" / "data" / "meshes" / "makehuman");
  tries.push_back(fs::current_path(ec) / "replay_data" / "makehuman");
  for (const fs::path& p : tries)
    if (fs::exists(p / "makehuman_hm08_body_only.obj", ec)) return p.string();
  return "../shared/data/meshes/makehuman";
}

}  // namespace skinstream::cli

namespace skinstream::cli {

std::string default_marker_sets_dir() {
  namespace fs = std::filesystem;
  if (const char* d = std::getenv("SKINSTREAM_MARKER_SETS_DIR")) return d;
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec)
    for (fs::path p = exe.parent_path(); !p.empty() && p != p.root_path(); p = p.parent_path())
      if (fs::is_directory(p / "config" / "marker_sets", ec)) return (p / "config" / "marker_sets").string();
  if (fs::is_directory(SKINSTREAM_BUNDLED_MARKER_SETS, ec)) return SKINSTREAM_BUNDLED_MARKER_SETS;  // the checkout built from
  return (fs::current_path(ec) / "config" / "marker_sets").string();
}

}  // namespace skinstream::cli
