#include "protocol/meshes/mesh_file.h"

#include <algorithm>
#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <string_view>

#include "protocol/files/file_error.h"
#include "protocol/files/whole_file.h"
#include "protocol/meshes/mesh_ply.h"

namespace skinstream {

namespace {

static_assert(std::endian::native == std::endian::little, "binary PLY reading assumes a little-endian host");

std::string lower_extension(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  const size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string ext = path.substr(dot);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

// Splits one line into whitespace-separated tokens (views into the line).
void split(std::string_view line, std::vector<std::string_view>& out) {
  out.clear();
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && is_space(line[i])) ++i;
    const size_t start = i;
    while (i < line.size() && !is_space(line[i])) ++i;
    if (i > start) out.push_back(line.substr(start, i - start));
  }
}

bool parse_double(std::string_view token, double& out) {
  if (!token.empty() && token[0] == '+') token.remove_prefix(1);
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), out);
  return ec == std::errc() && end == token.data() + token.size();
}

bool parse_integer(std::string_view token, long long& out) {
  if (!token.empty() && token[0] == '+') token.remove_prefix(1);
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), out);
  return ec == std::errc() && end == token.data() + token.size();
}

// Adds the fan v0 v1 v2, v0 v2 v3, ... of one polygon.
void add_fan(const std::vector<int>& polygon, std::vector<std::array<int, 3>>& faces) {
  for (size_t k = 1; k + 1 < polygon.size(); ++k) faces.push_back({polygon[0], polygon[k], polygon[k + 1]});
}

// Checks shared by both formats once the whole file is read.
void check_mesh(const TriangleMesh& mesh, const std::string& path) {
  for (size_t i = 0; i < mesh.vertices.size(); ++i)
    if (!mesh.vertices[i].allFinite()) throw FileError(path, "vertex " + std::to_string(i) + " has a non-finite coordinate");
  if (mesh.faces.empty()) throw FileError(path, "no faces");
  const int n = static_cast<int>(mesh.vertices.size());
  for (size_t f = 0; f < mesh.faces.size(); ++f)
    for (int v : mesh.faces[f])
      if (v < 0 || v >= n)
        throw FileError(path, "face index " + std::to_string(v) + " out of range (" + std::to_string(n) +
                                  " vertices) in triangle " + std::to_string(f));
}

// ---------------------------------------------------------------------------------------------
// Wavefront OBJ: "v x y z [w | r g b]" and "f i[/t[/n]] ..." lines; negative indices count back
// from the last vertex read. Other statements (vn, vt, g, o, s, usemtl, ...) are skipped; a line
// that does not start with a word is refused, which catches binary garbage.

TriangleMesh read_obj_file(const std::string& path, const std::string& bytes) {
  TriangleMesh mesh;
  std::vector<std::string_view> tokens;
  std::vector<int> polygon;
  size_t line_start = 0;
  for (int line_number = 1; line_start < bytes.size(); ++line_number) {
    size_t line_end = bytes.find('\n', line_start);
    if (line_end == std::string::npos) line_end = bytes.size();
    const std::string_view line(bytes.data() + line_start, line_end - line_start);
    line_start = line_end + 1;
    split(line, tokens);
    if (tokens.empty() || tokens[0][0] == '#') continue;
    const std::string where = "line " + std::to_string(line_number) + ": ";
    const std::string_view keyword = tokens[0];
    if (keyword == "v") {
      if (tokens.size() < 4 || tokens.size() > 8) throw FileError(path, where + "a vertex needs 3 coordinates");
      double xyz[3];
      for (size_t k = 1; k < tokens.size(); ++k) {
        double value = 0.0;
        if (!parse_double(tokens[k], value)) throw FileError(path, where + "bad number " + quoted_text(tokens[k]));
        if (k <= 3) xyz[k - 1] = value;
      }
      mesh.vertices.emplace_back(xyz[0], xyz[1], xyz[2]);
    } else if (keyword == "f") {
      if (tokens.size() < 4) throw FileError(path, where + "a face needs at least 3 vertices");
      polygon.clear();
      for (size_t k = 1; k < tokens.size(); ++k) {
        const std::string_view token = tokens[k];
        const std::string_view head = token.substr(0, token.find('/'));
        long long index = 0;
        if (!parse_integer(head, index) || index == 0 ||
            token.find_first_not_of("0123456789-/", head.size()) != std::string_view::npos)
          throw FileError(path, where + "bad face index " + quoted_text(token));
        // Negative: relative to the vertices read so far. Positive indices are checked at the
        // end, against every vertex in the file.
        const long long resolved = index > 0 ? index - 1 : static_cast<long long>(mesh.vertices.size()) + index;
        if (resolved < 0 || resolved > std::numeric_limits<int>::max())
          throw FileError(path, where + "face index " + std::to_string(index) + " out of range (" +
                                    std::to_string(mesh.vertices.size()) + " vertices so far)");
        polygon.push_back(static_cast<int>(resolved));
      }
      add_fan(polygon, mesh.faces);
    } else if (!std::isalpha(static_cast<unsigned char>(keyword[0])) ||
               !std::all_of(keyword.begin(), keyword.end(),
                            [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; })) {
      throw FileError(path, where + "not an OBJ statement: " + quoted_text(keyword));
    }
  }
  return mesh;
}

// ---------------------------------------------------------------------------------------------
// Stanford PLY: a text header of elements and their properties, then the data in ASCII or
// binary. Every element is read (unknown ones are skipped property by property), so the data
// must end exactly where the header says it does.

enum class PlyType { int8, uint8, int16, uint16, int32, uint32, float32, float64 };

bool ply_type(std::string_view name, PlyType& out) {
  static const std::pair<std::string_view, PlyType> names[] = {
      {"char", PlyType::int8},     {"int8", PlyType::int8},       {"uchar", PlyType::uint8},
      {"uint8", PlyType::uint8},   {"short", PlyType::int16},     {"int16", PlyType::int16},
      {"ushort", PlyType::uint16}, {"uint16", PlyType::uint16},   {"int", PlyType::int32},
      {"int32", PlyType::int32},   {"uint", PlyType::uint32},     {"uint32", PlyType::uint32},
      {"float", PlyType::float32}, {"float32", PlyType::float32}, {"double", PlyType::float64},
      {"float64", PlyType::float64}};
  for (const auto& [n, t] : names)
    if (n == name) {
      out = t;
      return true;
    }
  return false;
}

size_t ply_size(PlyType t) {
  switch (t) {
    case PlyType::int8:
    case PlyType::uint8: return 1;
    case PlyType::int16:
    case PlyType::uint16: return 2;
    case PlyType::int32:
    case PlyType::uint32:
    case PlyType::float32: return 4;
    case PlyType::float64: return 8;
  }
  return 0;
}

bool is_integer(PlyType t) { return t != PlyType::float32 && t != PlyType::float64; }

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::float32;  // the value type (the items, for a list)
  bool is_list = false;
  PlyType count_type = PlyType::uint8;
};

struct PlyElement {
  std::string name;
  size_t count = 0;
  std::vector<PlyProperty> properties;
};

enum class PlyFormat { ascii, binary_little_endian, binary_big_endian };

struct PlyHeader {
  PlyFormat format = PlyFormat::ascii;
  std::vector<PlyElement> elements;
  size_t data_offset = 0;
};

PlyHeader read_ply_header(const std::string& path, const std::string& bytes) {
  PlyHeader header;
  std::vector<std::string_view> tokens;
  size_t pos = 0;
  bool have_format = false;
  for (int line_number = 1;; ++line_number) {
    const size_t end = bytes.find('\n', pos);
    if (end == std::string::npos) throw FileError(path, "truncated PLY header (no end_header)");
    std::string_view line(bytes.data() + pos, end - pos);
    pos = end + 1;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    const std::string where = "header line " + std::to_string(line_number) + ": ";
    if (line_number == 1) {
      if (line != "ply") throw FileError(path, "not a PLY file (first line is not 'ply')");
      continue;
    }
    split(line, tokens);
    if (tokens.empty()) continue;
    const std::string_view keyword = tokens[0];
    if (keyword == "end_header") break;
    if (keyword == "comment" || keyword == "obj_info") continue;
    if (keyword == "format") {
      if (tokens.size() != 3 || tokens[2] != "1.0") throw FileError(path, where + "unsupported format line");
      if (tokens[1] == "ascii") header.format = PlyFormat::ascii;
      else if (tokens[1] == "binary_little_endian") header.format = PlyFormat::binary_little_endian;
      else if (tokens[1] == "binary_big_endian") header.format = PlyFormat::binary_big_endian;
      else throw FileError(path, where + "unknown format " + quoted_text(tokens[1]));
      have_format = true;
    } else if (keyword == "element") {
      long long count = 0;
      if (tokens.size() != 3 || !parse_integer(tokens[2], count) || count < 0 ||
          count > std::numeric_limits<int>::max())
        throw FileError(path, where + "bad element line");
      header.elements.push_back({std::string(tokens[1]), static_cast<size_t>(count), {}});
    } else if (keyword == "property") {
      if (header.elements.empty()) throw FileError(path, where + "property before any element");
      PlyProperty p;
      if (tokens.size() == 5 && tokens[1] == "list") {
        p.is_list = true;
        if (!ply_type(tokens[2], p.count_type) || !is_integer(p.count_type) || !ply_type(tokens[3], p.type))
          throw FileError(path, where + "bad list property");
        p.name = tokens[4];
      } else if (tokens.size() == 3) {
        if (!ply_type(tokens[1], p.type)) throw FileError(path, where + "unknown property type " + quoted_text(tokens[1]));
        p.name = tokens[2];
      } else {
        throw FileError(path, where + "bad property line");
      }
      header.elements.back().properties.push_back(p);
    } else {
      throw FileError(path, where + "unknown header keyword " + quoted_text(keyword));
    }
  }
  if (!have_format) throw FileError(path, "PLY header has no format line");
  header.data_offset = pos;
  return header;
}

// Reads values one at a time from the data section, in either encoding.
class PlyData {
 public:
  PlyData(const std::string& path, const std::string& bytes, const PlyHeader& header)
      : path_(path), bytes_(bytes), format_(header.format), pos_(header.data_offset) {}

  size_t remaining() const { return bytes_.size() - pos_; }
  bool binary() const { return format_ != PlyFormat::ascii; }

  // ASCII: each element instance is one line.
  void begin_instance(const std::string& what) {
    if (format_ != PlyFormat::ascii) return;
    for (;;) {
      if (pos_ >= bytes_.size()) throw FileError(path_, "truncated: file ends before " + what);
      size_t end = bytes_.find('\n', pos_);
      if (end == std::string::npos) end = bytes_.size();
      split(std::string_view(bytes_.data() + pos_, end - pos_), tokens_);
      pos_ = std::min(end + 1, bytes_.size());
      if (!tokens_.empty()) break;
    }
    next_token_ = 0;
    what_ = what;
  }
  void end_instance() {
    if (format_ == PlyFormat::ascii && next_token_ != tokens_.size())
      throw FileError(path_, "corrupt: extra values in " + what_);
  }

  double value(PlyType type, const std::string& what) {
    if (format_ == PlyFormat::ascii) return ascii_value(type);
    const size_t n = ply_size(type);
    if (remaining() < n) throw FileError(path_, "truncated: file ends in " + what);
    unsigned char raw[8];
    std::memcpy(raw, bytes_.data() + pos_, n);
    pos_ += n;
    if (format_ == PlyFormat::binary_big_endian) std::reverse(raw, raw + n);
    switch (type) {
      case PlyType::int8: return static_cast<int8_t>(raw[0]);
      case PlyType::uint8: return raw[0];
      case PlyType::int16: return load<int16_t>(raw);
      case PlyType::uint16: return load<uint16_t>(raw);
      case PlyType::int32: return load<int32_t>(raw);
      case PlyType::uint32: return load<uint32_t>(raw);
      case PlyType::float32: return load<float>(raw);
      case PlyType::float64: return load<double>(raw);
    }
    return 0.0;
  }

  void check_fully_read() const {
    if (format_ == PlyFormat::ascii) {
      for (size_t i = pos_; i < bytes_.size(); ++i)
        if (!is_space(bytes_[i]) && bytes_[i] != '\n') throw FileError(path_, "corrupt: data after the last element");
    } else if (remaining() != 0) {
      throw FileError(path_, "corrupt: " + std::to_string(remaining()) + " bytes after the last element");
    }
  }

 private:
  template <typename T>
  static double load(const unsigned char* raw) {
    T v;
    std::memcpy(&v, raw, sizeof v);
    return static_cast<double>(v);
  }

  double ascii_value(PlyType type) {
    if (next_token_ >= tokens_.size()) throw FileError(path_, "corrupt: too few values in " + what_);
    const std::string_view token = tokens_[next_token_++];
    if (is_integer(type)) {
      long long v = 0;
      if (!parse_integer(token, v)) throw FileError(path_, "corrupt: bad integer " + quoted_text(token) + " in " + what_);
      return static_cast<double>(v);
    }
    double v = 0.0;
    if (!parse_double(token, v)) throw FileError(path_, "corrupt: bad number " + quoted_text(token) + " in " + what_);
    return v;
  }

  const std::string& path_;
  const std::string& bytes_;
  PlyFormat format_;
  size_t pos_;
  std::vector<std::string_view> tokens_;
  size_t next_token_ = 0;
  std::string what_;
};

int property_index(const PlyElement& e, std::initializer_list<std::string_view> names, bool list) {
  for (size_t i = 0; i < e.properties.size(); ++i)
    for (std::string_view n : names)
      if (e.properties[i].name == n && e.properties[i].is_list == list) return static_cast<int>(i);
  return -1;
}

TriangleMesh read_ply_file(const std::string& path, const std::string& bytes) {
  const PlyHeader header = read_ply_header(path, bytes);
  PlyData data(path, bytes, header);
  TriangleMesh mesh;
  bool have_vertices = false, have_faces = false;
  std::vector<int> polygon;
  for (const PlyElement& e : header.elements) {
    // Refuse counts the file cannot hold before reserving anything for them.
    size_t least_bytes = 0;
    for (const PlyProperty& p : e.properties)
      least_bytes += header.format == PlyFormat::ascii ? 2 : ply_size(p.is_list ? p.count_type : p.type);
    if (least_bytes > 0 && e.count > (data.remaining() + 1) / least_bytes)
      throw FileError(path, "truncated: header says " + std::to_string(e.count) + " " + e.name +
                                " elements, the file is too short for them");
    const bool is_vertex = e.name == "vertex";
    const bool is_face = e.name == "face";
    int xyz[3] = {-1, -1, -1};
    int indices = -1;
    if (is_vertex) {
      if (have_vertices) throw FileError(path, "two vertex elements");
      xyz[0] = property_index(e, {"x"}, false);
      xyz[1] = property_index(e, {"y"}, false);
      xyz[2] = property_index(e, {"z"}, false);
      if (xyz[0] < 0 || xyz[1] < 0 || xyz[2] < 0) throw FileError(path, "vertex element lacks x, y or z");
      have_vertices = true;
      mesh.vertices.reserve(e.count);
    }
    if (is_face) {
      if (have_faces) throw FileError(path, "two face elements");
      indices = property_index(e, {"vertex_indices", "vertex_index"}, true);
      if (indices < 0 || !is_integer(e.properties[static_cast<size_t>(indices)].type))
        throw FileError(path, "face element lacks an integer vertex_indices list");
      have_faces = true;
      mesh.faces.reserve(e.count);
    }
    for (size_t i = 0; i < e.count; ++i) {
      const std::string what = e.name + " " + std::to_string(i);
      data.begin_instance(what);
      Vec3 point = Vec3::Zero();
      for (size_t k = 0; k < e.properties.size(); ++k) {
        const PlyProperty& p = e.properties[k];
        if (!p.is_list) {
          const double v = data.value(p.type, what);
          for (int c = 0; c < 3; ++c)
            if (xyz[c] == static_cast<int>(k)) point[c] = v;
          continue;
        }
        const double count = data.value(p.count_type, what);
        const bool wanted = static_cast<int>(k) == indices;
        if (count < 0 || (wanted && count < 3))
          throw FileError(path, "corrupt: " + what + " has " + std::to_string(static_cast<long long>(count)) +
                                    " vertices");
        // (ASCII lists are bounded by the values on their line.)
        if (data.binary() && count * static_cast<double>(ply_size(p.type)) > static_cast<double>(data.remaining()))
          throw FileError(path, "truncated: file ends in " + what);
        if (wanted) polygon.clear();
        for (long long j = 0; j < static_cast<long long>(count); ++j) {
          const double v = data.value(p.type, what);
          if (wanted) {
            if (v < 0 || v > std::numeric_limits<int>::max())
              throw FileError(path, "face index " + std::to_string(static_cast<long long>(v)) + " out of range in " + what);
            polygon.push_back(static_cast<int>(v));
          }
        }
        if (wanted) add_fan(polygon, mesh.faces);
      }
      data.end_instance();
      if (is_vertex) mesh.vertices.push_back(point);
    }
  }
  data.check_fully_read();
  if (!have_vertices) throw FileError(path, "no vertex element");
  if (!have_faces) throw FileError(path, "no faces");
  return mesh;
}

// The path's extension when it names a mesh format (.obj or .ply); a FileError otherwise.
std::string mesh_extension(const std::string& path) {
  const std::string ext = lower_extension(path);
  if (ext != ".obj" && ext != ".ply")
    throw FileError(path, "unknown mesh extension '" + ext + "' (expected .obj or .ply)");
  return ext;
}

TriangleMesh parse_mesh(const std::string& path, const std::string& ext, const std::string& bytes) {
  if (bytes.empty()) throw FileError(path, "empty file");
  TriangleMesh mesh = ext == ".obj" ? read_obj_file(path, bytes) : read_ply_file(path, bytes);
  check_mesh(mesh, path);
  return mesh;
}

}  // namespace

TriangleMesh read_mesh(const std::string& path) {
  const std::string ext = mesh_extension(path);
  return parse_mesh(path, ext, read_whole_file(path));
}

TriangleMesh read_mesh_bytes(std::string_view bytes, const std::string& name) {
  return parse_mesh(name, mesh_extension(name), std::string(bytes));
}

namespace {

void check_faces_for_writing(const std::string& path, size_t vertex_count, const std::vector<std::array<int, 3>>& faces) {
  for (size_t f = 0; f < faces.size(); ++f)
    for (int v : faces[f])
      if (v < 0 || static_cast<size_t>(v) >= vertex_count)
        throw FileError(path, "triangle " + std::to_string(f) + " uses vertex " + std::to_string(v) + " of " +
                                  std::to_string(vertex_count));
}

// Shortest text that reads back to the same double.
void append_number(std::string& out, double value) {
  char buffer[32];
  const auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, value);
  out.append(buffer, ec == std::errc() ? end : buffer);
}

void append_triple(std::string& out, const char* keyword, const Vec3& v) {
  out += keyword;
  for (int c = 0; c < 3; ++c) {
    out += ' ';
    append_number(out, v[c]);
  }
  out += '\n';
}

}  // namespace

void write_obj(const std::string& path, const std::vector<Vec3>& vertices,
               const std::vector<std::array<int, 3>>& faces, const std::vector<Vec3>* normals) {
  check_faces_for_writing(path, vertices.size(), faces);
  if (normals && normals->size() != vertices.size())
    throw FileError(path, std::to_string(normals->size()) + " normals for " + std::to_string(vertices.size()) + " vertices");
  std::string text = "# skinstream mesh: " + std::to_string(vertices.size()) + " vertices, " +
                     std::to_string(faces.size()) + " triangles\n";
  text.reserve(text.size() + vertices.size() * (normals ? 80 : 40) + faces.size() * 30);
  for (const Vec3& v : vertices) append_triple(text, "v", v);
  if (normals)
    for (const Vec3& n : *normals) append_triple(text, "vn", n);
  for (const auto& f : faces) {
    text += 'f';
    for (int v : f) {
      const std::string index = std::to_string(v + 1);
      text += ' ';
      text += index;
      if (normals) text += "//" + index;
    }
    text += '\n';
  }
  std::ofstream out(path, std::ios::binary);
  if (!out) throw FileError(path, "cannot create");
  out.write(text.data(), static_cast<std::streamsize>(text.size()));
  if (!out) throw FileError(path, "write failed");
}

void write_obj(const std::string& path, const TriangleMesh& mesh) { write_obj(path, mesh.vertices, mesh.faces); }

void write_ply(const std::string& path, const std::vector<Vec3>& vertices,
               const std::vector<std::array<int, 3>>& faces) {
  std::vector<Face> polygons;
  polygons.reserve(faces.size());
  for (const auto& f : faces) polygons.push_back({f[0], f[1], f[2], -1});
  write_ply(path, vertices, polygons);
}

void write_ply(const std::string& path, const TriangleMesh& mesh) { write_ply(path, mesh.vertices, mesh.faces); }

}  // namespace skinstream
