#pragma once
// Where the offline tool finds shared data when not told.
#include <string>

namespace skinstream::cli {

// The MakeHuman body folder: $SKINSTREAM_MAKEHUMAN_DIR, else $SKINSTREAM_SHARED_DIR/data/meshes/
// makehuman, else shared/data/meshes/makehuman or the bundled replay_data/makehuman beside an
// ancestor of the executable, else either from the working directory.
std::string default_body_dir();

// The shipped marker-set definitions: $SKINSTREAM_MARKER_SETS_DIR, else config/marker_sets
// beside an ancestor of the executable (the source tree of a build), else from the working
// directory.
std::string default_marker_sets_dir();

}  // namespace skinstream::cli
