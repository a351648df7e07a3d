#pragma once
// Where the offline tool finds shared data when not told.
#include <string>

namespace skinstream::cli {

// The MakeHuman body folder: $SKINSTREAM_MAKEHUMAN_DIR, else $SKINSTREAM_SHARED_DIR/data/meshes/
// makehuman, else shared/data/meshes/makehuman or the bundled replay_data/makehuman beside an
// ancestor of the executable, else either from the working directory.
std::string default_body_dir();

}  // namespace skinstream::cli
