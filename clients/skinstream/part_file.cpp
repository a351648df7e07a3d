#include "clients/skinstream/part_file.h"

#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>

#include "protocol/files/file_error.h"

namespace skinstream::cli {

std::vector<int> read_marker_map(const std::string& path, const SubjectModel& model, const char* what) {
  std::ifstream in(path);
  if (!in) throw FileError(path, "cannot open");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw FileError(path, std::string("not valid JSON: ") + e.what());
  }
  if (!j.is_object()) throw FileError(path, std::string("expected an object {\"marker name\": ") + what + "}");
  std::vector<int> out(model.marker_count(), -1);
  for (const auto& [name, value] : j.items()) {
    const int i = model.marker_index(name);
    if (i < 0) throw FileError(path, "unknown marker \"" + name + "\"");
    if (!value.is_number_integer() || value.get<int>() < 0) throw FileError(path, "\"" + name + "\": expected a non-negative integer " + what);
    out[i] = value.get<int>();
  }
  return out;
}

std::vector<int> read_part_file(const std::string& path, const SubjectModel& model) {
  std::vector<int> part = read_marker_map(path, model, "part index");
  std::vector<char> in_triangle(model.marker_count(), 0);
  for (const auto& t : model.triangles)
    for (int v : t) in_triangle[v] = 1;
  for (int i = 0; i < model.marker_count(); ++i)
    if (part[i] < 0) {
      if (in_triangle[i]) throw FileError(path, "marker " + model.marker_names[i] + " has no part");
      part[i] = 0;
    }
  return part;
}

void write_part_file(const std::string& path, const SubjectModel& model, const std::vector<int>& marker_part) {
  nlohmann::ordered_json j = nlohmann::ordered_json::object();
  for (int i = 0; i < model.marker_count(); ++i)
    if (marker_part[i] >= 0) j[model.marker_names[i]] = marker_part[i];
  std::ofstream out(path);
  if (!(out << j.dump(1) << '\n')) throw FileError(path, "cannot write");
}

void warn_unused_parts(const std::string& path, const std::vector<int>& unused) {
  if (unused.empty()) return;
  std::string list;
  for (int p : unused) list += (list.empty() ? "" : ", ") + std::to_string(p);
  std::fprintf(stderr,
               "skinstream: warning: %s: part(s) %s hold no triangle of the marker surface (a triangle takes the part "
               "most of its markers have); dropped, the other parts renumbered in order\n",
               path.c_str(), list.c_str());
}

}  // namespace skinstream::cli
