#pragma once
// The marker surface as a Wavefront OBJ: vertex i is subject marker i (a comment line names
// it), faces are the triangles. A user can export it, edit it in any modelling tool that keeps
// the vertex order, and give it back to `skinstream build-subject --surface`.

#include <array>
#include <string>
#include <vector>

#include "core/capture.h"

namespace skinstream {

void write_marker_surface_obj(const std::string& path, const std::vector<std::string>& names,
                              const std::vector<Vec3>& positions, const std::vector<std::array<int, 3>>& triangles);

// Triangles of an OBJ (polygons are fanned); checks the vertex count is `expected_vertices`.
std::vector<std::array<int, 3>> read_marker_surface_obj(const std::string& path, int expected_vertices);

}  // namespace skinstream
