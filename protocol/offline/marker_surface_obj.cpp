#include "protocol/offline/marker_surface_obj.h"

#include <cstdlib>
#include <fstream>
#include <sstream>

#include "protocol/files/file_error.h"

namespace skinstream {

void write_marker_surface_obj(const std::string& path, const std::vector<std::string>& names,
                              const std::vector<Vec3>& positions, const std::vector<std::array<int, 3>>& triangles) {
  std::ofstream out(path);
  if (!out) throw FileError(path, "cannot open for writing");
  out << "# skinstream marker surface: vertex i is subject marker i (mm)\n";
  for (size_t i = 0; i < positions.size(); ++i)
    out << "# marker " << i << ' ' << names[i] << "\nv " << positions[i].x() << ' ' << positions[i].y() << ' '
        << positions[i].z() << '\n';
  for (const auto& t : triangles) out << "f " << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << '\n';
  if (!out) throw FileError(path, "write failed");
}

std::vector<std::array<int, 3>> read_marker_surface_obj(const std::string& path, int expected_vertices) {
  std::ifstream in(path);
  if (!in) throw FileError(path, "cannot open marker surface");
  std::vector<std::array<int, 3>> triangles;
  int vertices = 0;
  std::string line;
  for (int line_number = 1; std::getline(in, line); ++line_number) {
    std::istringstream fields(line);
    std::string tag;
    fields >> tag;
    if (tag == "v") {
      ++vertices;
    } else if (tag == "f") {
      std::vector<int> face;
      std::string corner;
      while (fields >> corner) {
        char* end = nullptr;
        long index = std::strtol(corner.c_str(), &end, 10);  // "v", "v/vt", "v//vn", "v/vt/vn"
        if (end == corner.c_str()) throw FileError(path, "line " + std::to_string(line_number) + ": bad face index '" + corner + "'");
        if (index < 0) index += vertices + 1;  // relative indices
        if (index < 1 || index > expected_vertices)
          throw FileError(path, "line " + std::to_string(line_number) + ": face index " + corner + " outside 1.." +
                                    std::to_string(expected_vertices));
        face.push_back(static_cast<int>(index - 1));
      }
      if (face.size() < 3) throw FileError(path, "line " + std::to_string(line_number) + ": face with fewer than 3 vertices");
      for (size_t k = 1; k + 1 < face.size(); ++k) triangles.push_back({face[0], face[k], face[k + 1]});
    }
  }
  if (vertices != expected_vertices)
    throw FileError(path, "has " + std::to_string(vertices) + " vertices, the subject has " + std::to_string(expected_vertices) +
                              " markers (vertex i must be marker i)");
  if (triangles.empty()) throw FileError(path, "no faces");
  return triangles;
}

}  // namespace skinstream
