#include "protocol/offline/makehuman.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <unordered_map>

#include "protocol/files/file_error.h"
#include "protocol/files/whole_file.h"

namespace skinstream {

namespace {


nlohmann::json read_json(const std::string& path) {
  try {
    return nlohmann::json::parse(read_whole_file(path));
  } catch (const nlohmann::json::exception& e) {
    throw FileError(path, std::string("not valid JSON: ") + e.what());
  }
}

int obj_index(const std::string& token, int vertex_count, const std::string& path, int line) {
  const std::string head = token.substr(0, token.find('/'));
  int i = 0;
  try {
    size_t used = 0;
    i = std::stoi(head, &used);
    if (used != head.size()) throw std::invalid_argument(head);
  } catch (const std::exception&) {
    throw FileError(path, "line " + std::to_string(line) + ": bad face index '" + token + "'");
  }
  const int index = i > 0 ? i - 1 : vertex_count + i;  // negative = relative to the end
  if (i == 0 || index < 0 || index >= vertex_count)
    throw FileError(path, "line " + std::to_string(line) + ": face index " + std::to_string(i) +
                              " out of range (" + std::to_string(vertex_count) + " vertices so far)");
  return index;
}

std::pair<Vec3, Vec3> joint_pair(const nlohmann::json& bone, const std::map<std::string, Vec3>& joints,
                                 const std::string& name, const std::string& path) {
  Vec3 ends[2];
  const char* keys[2] = {"head", "tail"};
  for (int k = 0; k < 2; ++k) {
    if (!bone.contains(keys[k]) || !bone[keys[k]].is_string())
      throw FileError(path, "bone " + name + " has no " + keys[k] + " joint");
    const std::string joint = bone[keys[k]].get<std::string>();
    auto it = joints.find(joint);
    if (it == joints.end()) throw FileError(path, "bone " + name + " names unknown joint " + joint);
    ends[k] = it->second;
  }
  return {ends[0], ends[1]};
}

}  // namespace

MakeHumanFiles MakeHumanFiles::in(const std::string& dir) {
  const std::string d = dir.empty() || dir.back() == '/' ? dir : dir + "/";
  return {d + "makehuman_hm08_body_only.obj", d + "base.obj", d + "default.mhskel",
          d + "default_weights.mhw"};
}

ObjMesh read_obj(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw FileError(path, "cannot open");
  ObjMesh mesh;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (line.size() < 2) continue;
    if (line[0] == 'v' && line[1] == ' ') {
      std::istringstream s(line.substr(2));
      double x, y, z;
      if (!(s >> x >> y >> z) || !std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z))
        throw FileError(path, "line " + std::to_string(number) + ": bad vertex");
      mesh.vertices.emplace_back(x, y, z);
    } else if (line[0] == 'f' && line[1] == ' ') {
      std::istringstream s(line.substr(2));
      std::vector<int> poly;
      std::string token;
      while (s >> token)
        poly.push_back(obj_index(token, static_cast<int>(mesh.vertices.size()), path, number));
      if (poly.size() < 3)
        throw FileError(path, "line " + std::to_string(number) + ": face with fewer than 3 vertices");
      if (poly.size() == 3) {
        mesh.faces.push_back({poly[0], poly[1], poly[2], -1});
      } else if (poly.size() == 4) {
        mesh.faces.push_back({poly[0], poly[1], poly[2], poly[3]});
      } else {
        for (size_t k = 1; k + 1 < poly.size(); ++k)
          mesh.faces.push_back({poly[0], poly[k], poly[k + 1], -1});
      }
    }
  }
  if (mesh.vertices.empty()) throw FileError(path, "no vertices");
  return mesh;
}

std::vector<int> match_vertices(const std::vector<Vec3>& part, const std::vector<Vec3>& whole,
                                double tolerance) {
  // Hash on a grid of cell `tolerance`; look in the neighbouring cells.
  auto cell = [tolerance](double v) { return static_cast<int64_t>(std::floor(v / tolerance)); };
  auto key = [](int64_t x, int64_t y, int64_t z) {
    return static_cast<uint64_t>(x * 73856093) ^ static_cast<uint64_t>(y * 19349663) ^
           static_cast<uint64_t>(z * 83492791);
  };
  std::unordered_multimap<uint64_t, int> grid;
  grid.reserve(whole.size() * 2);
  for (size_t i = 0; i < whole.size(); ++i)
    grid.emplace(key(cell(whole[i].x()), cell(whole[i].y()), cell(whole[i].z())), static_cast<int>(i));
  std::vector<int> out(part.size(), -1);
  for (size_t i = 0; i < part.size(); ++i) {
    const Vec3& p = part[i];
    double best = std::numeric_limits<double>::infinity();
    const int64_t cx = cell(p.x()), cy = cell(p.y()), cz = cell(p.z());
    for (int64_t dx = -1; dx <= 1; ++dx)
      for (int64_t dy = -1; dy <= 1; ++dy)
        for (int64_t dz = -1; dz <= 1; ++dz) {
          auto range = grid.equal_range(key(cx + dx, cy + dy, cz + dz));
          for (auto it = range.first; it != range.second; ++it) {
            const double d = (whole[static_cast<size_t>(it->second)] - p).norm();
            if (d > tolerance) continue;
            const bool same_index = it->second == static_cast<int>(i);
            if (d < best || (same_index && d <= best)) {
              best = same_index ? -1.0 : d;  // the same index wins ties for good
              out[i] = it->second;
            }
          }
        }
  }
  return out;
}

Body load_makehuman(const std::string& dir) { return load_makehuman(MakeHumanFiles::in(dir)); }

Body load_makehuman(const MakeHumanFiles& files) {
  const ObjMesh body_mesh = read_obj(files.body_obj);
  const ObjMesh base_mesh = read_obj(files.base_obj);
  const std::vector<int> to_base = match_vertices(body_mesh.vertices, base_mesh.vertices);
  std::vector<int> to_body(base_mesh.vertices.size(), -1);
  for (size_t i = 0; i < to_base.size(); ++i) {
    if (to_base[i] < 0)
      throw FileError(files.base_obj, "has no vertex at the position of body vertex " + std::to_string(i));
    to_body[static_cast<size_t>(to_base[i])] = static_cast<int>(i);
  }

  // Skeleton: joints from base.obj vertices, bones ordered parents first.
  const nlohmann::json skel = read_json(files.skeleton);
  if (!skel.contains("joints") || !skel["joints"].is_object() || !skel.contains("bones") ||
      !skel["bones"].is_object())
    throw FileError(files.skeleton, "needs 'joints' and 'bones' objects");
  std::map<std::string, Vec3> joints;
  for (const auto& [name, list] : skel["joints"].items()) {
    if (!list.is_array() || list.empty())
      throw FileError(files.skeleton, "joint " + name + " lists no vertices");
    Vec3 sum = Vec3::Zero();
    for (const auto& v : list) {
      if (!v.is_number_integer())
        throw FileError(files.skeleton, "joint " + name + " has a non-integer vertex");
      const int64_t i = v.get<int64_t>();
      if (i < 0 || i >= static_cast<int64_t>(base_mesh.vertices.size()))
        throw FileError(files.skeleton, "joint " + name + " uses vertex " + std::to_string(i) + " of " +
                                            std::to_string(base_mesh.vertices.size()) + " in base.obj");
      sum += base_mesh.vertices[static_cast<size_t>(i)];
    }
    joints[name] = sum / static_cast<double>(list.size());
  }
  const auto& bones_json = skel["bones"];
  std::map<std::string, std::vector<std::string>> children;
  std::vector<std::string> roots;
  for (const auto& [name, bone] : bones_json.items()) {
    if (!bone.is_object()) throw FileError(files.skeleton, "bone " + name + " is not an object");
    if (!bone.contains("parent") || bone["parent"].is_null()) {
      roots.push_back(name);
    } else {
      if (!bone["parent"].is_string()) throw FileError(files.skeleton, "bone " + name + " has a bad parent");
      const std::string parent = bone["parent"].get<std::string>();
      if (!bones_json.contains(parent))
        throw FileError(files.skeleton, "bone " + name + " has unknown parent " + parent);
      children[parent].push_back(name);
    }
  }
  std::vector<Bone> bones;
  std::map<std::string, int> bone_index;
  std::vector<std::pair<std::string, int>> stack;
  for (auto it = roots.rbegin(); it != roots.rend(); ++it) stack.emplace_back(*it, -1);
  while (!stack.empty()) {
    const auto [name, parent] = stack.back();
    stack.pop_back();
    const auto [head, tail] = joint_pair(bones_json[name], joints, name, files.skeleton);
    Bone b;
    b.name = name;
    b.parent = parent;
    b.head = head;
    b.tail = tail;
    bone_index[name] = static_cast<int>(bones.size());
    bones.push_back(b);
    auto& kids = children[name];
    for (auto it = kids.rbegin(); it != kids.rend(); ++it) stack.emplace_back(*it, bone_index[name]);
  }
  if (bones.size() != bones_json.size()) throw FileError(files.skeleton, "bone hierarchy has a cycle");

  // Weights.
  const nlohmann::json wj = read_json(files.weights);
  if (!wj.contains("weights") || !wj["weights"].is_object())
    throw FileError(files.weights, "needs a 'weights' object");
  std::vector<std::vector<std::pair<int, double>>> rows(body_mesh.vertices.size());
  for (const auto& [name, list] : wj["weights"].items()) {
    auto bi = bone_index.find(name);
    if (bi == bone_index.end()) throw FileError(files.weights, "weights for unknown bone " + name);
    if (!list.is_array()) throw FileError(files.weights, "weights of " + name + " are not a list");
    for (const auto& pair : list) {
      if (!pair.is_array() || pair.size() != 2 || !pair[0].is_number_integer() || !pair[1].is_number())
        throw FileError(files.weights, "bad [vertex, weight] pair for bone " + name);
      const int64_t v = pair[0].get<int64_t>();
      const double w = pair[1].get<double>();
      if (v < 0 || v >= static_cast<int64_t>(base_mesh.vertices.size()))
        throw FileError(files.weights, "bone " + name + " weights vertex " + std::to_string(v) + " of " +
                                           std::to_string(base_mesh.vertices.size()));
      if (!std::isfinite(w) || w < 0.0)
        throw FileError(files.weights, "bone " + name + " has weight " + std::to_string(w));
      const int body_v = to_body[static_cast<size_t>(v)];
      if (body_v >= 0) rows[static_cast<size_t>(body_v)].emplace_back(bi->second, w);
    }
  }

  // Convert to millimetres, Z up; soles at z = 0, hip centre over the origin.
  Body body;
  body.rest.reserve(body_mesh.vertices.size());
  for (const Vec3& p : body_mesh.vertices) body.rest.push_back(makehuman_to_skinstream(p));
  for (Bone& b : bones) {
    b.head = makehuman_to_skinstream(b.head);
    b.tail = makehuman_to_skinstream(b.tail);
  }
  double min_z = std::numeric_limits<double>::infinity();
  for (const Vec3& p : body.rest) min_z = std::min(min_z, p.z());
  Vec3 hip = Vec3::Zero();
  int hips = 0;
  for (const char* n : {"upperleg01.L", "upperleg01.R"}) {
    auto it = bone_index.find(n);
    if (it != bone_index.end()) {
      hip += bones[static_cast<size_t>(it->second)].head;
      ++hips;
    }
  }
  const Vec3 shift = hips ? Vec3(-hip.x() / hips, -hip.y() / hips, -min_z) : Vec3(0.0, 0.0, -min_z);
  for (Vec3& p : body.rest) p += shift;
  for (Bone& b : bones) {
    b.head += shift;
    b.tail += shift;
  }
  body.faces = body_mesh.faces;
  try {
    body.skeleton = Skeleton(bones);
    body.weights = SkinWeights::from_lists(rows, body.skeleton.size());
    validate(body);
  } catch (const std::invalid_argument& e) {
    throw FileError(files.weights, e.what());
  }
  // Faces counter-clockwise seen from outside.
  if (signed_volume(body.rest, triangulate(body.faces)) < 0.0)
    for (Face& f : body.faces) {
      if (f[3] >= 0)
        std::swap(f[1], f[3]);
      else
        std::swap(f[1], f[2]);
    }
  return body;
}

}  // namespace skinstream
