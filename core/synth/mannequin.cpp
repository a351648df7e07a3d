#include "core/synth/mannequin.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>

namespace skinstream::synth {

namespace {

struct BoneDef {
  const char* name;
  const char* parent;
  Vec3 head, tail;  // left side for sided bones (x <= 0)
};

// MakeHuman's default skeleton joints, rounded, in mm (Z up, facing +Y, left on -X).
const BoneDef kBones[] = {
    {"root", nullptr, {0, -76, 873}, {0, 14, 890}},
    {"spine05", "root", {0, 14, 890}, {0, -10, 936}},
    {"spine04", "spine05", {0, -10, 936}, {0, 15, 1004}},
    {"spine03", "spine04", {0, 15, 1004}, {0, 26, 1097}},
    {"spine02", "spine03", {0, 26, 1097}, {0, -7, 1250}},
    {"spine01", "spine02", {0, -7, 1250}, {0, 7, 1406}},
    {"neck01", "spine01", {0, 7, 1406}, {0, 22, 1444}},
    {"neck02", "neck01", {0, 22, 1444}, {0, 34, 1479}},
    {"neck03", "neck02", {0, 34, 1479}, {0, 16, 1514}},
    {"head", "neck03", {0, 16, 1514}, {0, 8, 1657}},
    {"breast.*", "spine02", {0, -7, 1250}, {-79, 158, 1199}},
    {"clavicle.*", "spine01", {-27, 69, 1336}, {-118, 51, 1369}},
    {"shoulder01.*", "clavicle.*", {-118, 51, 1369}, {-168, 15, 1342}},
    {"upperarm01.*", "shoulder01.*", {-168, 15, 1342}, {-206, 12, 1293}},
    {"upperarm02.*", "upperarm01.*", {-206, 12, 1293}, {-313, 13, 1166}},
    {"lowerarm01.*", "upperarm02.*", {-313, 13, 1166}, {-372, 94, 1114}},
    {"lowerarm02.*", "lowerarm01.*", {-372, 94, 1114}, {-431, 176, 1062}},
    {"wrist.*", "lowerarm02.*", {-431, 176, 1062}, {-429, 197, 1040}},
    {"pelvis.*", "root", {0, 14, 890}, {-110, 12, 866}},
    {"upperleg01.*", "pelvis.*", {-110, 12, 866}, {-108, 23, 785}},
    {"upperleg02.*", "upperleg01.*", {-108, 23, 785}, {-158, 32, 448}},
    {"lowerleg01.*", "upperleg02.*", {-158, 32, 448}, {-189, 16, 260}},
    {"lowerleg02.*", "lowerleg01.*", {-189, 16, 260}, {-220, -1, 72}},
    {"foot.*", "lowerleg02.*", {-220, -1, 72}, {-220, 60, 40}},
};

std::string sided(const char* name, char side) {
  std::string s(name);
  const auto star = s.find('*');
  if (star != std::string::npos) s[star] = side;
  return s;
}

Vec3 mirror(const Vec3& p, char side) { return side == 'R' ? Vec3(-p.x(), p.y(), p.z()) : p; }

double segment_distance(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double t = std::clamp((p - a).dot(ab) / std::max(ab.squaredNorm(), 1e-12), 0.0, 1.0);
  return (p - (a + t * ab)).norm();
}

struct Builder {
  Body body;
  std::vector<std::vector<std::pair<int, double>>> rows;

  // A closed tube from a to b with elliptic sections: width(s), depth(s) (semi-axes along u and
  // w), centre shift(s) along w, s in [0, 1]; rounded caps; weights from the listed bones.
  void tube(const Vec3& a, const Vec3& b, const Vec3& u_hint, int segments, int rings,
            const std::function<double(double)>& width, const std::function<double(double)>& depth,
            const std::function<double(double)>& shift, double cap_start, double cap_end,
            const std::vector<std::string>& bone_names) {
    const Vec3 d = (b - a).normalized();
    const Vec3 u = (u_hint - u_hint.dot(d) * d).normalized();
    const Vec3 w = d.cross(u);
    std::vector<int> bones;
    for (const auto& nm : bone_names) {
      const int i = body.skeleton.find(nm);
      if (i >= 0) bones.push_back(i);
    }
    struct Ring {
      double s, scale, along;  // parameter, section scale, extra offset along d (caps)
    };
    std::vector<Ring> list;
    constexpr int kCap = 4;
    for (int i = 1; i < kCap; ++i) {
      const double phi = 0.5 * M_PI * i / kCap;
      list.push_back({0.0, std::sin(phi), -cap_start * std::cos(phi)});
    }
    for (int i = 0; i <= rings; ++i) list.push_back({static_cast<double>(i) / rings, 1.0, 0.0});
    for (int i = kCap - 1; i >= 1; --i) {
      const double phi = 0.5 * M_PI * i / kCap;
      list.push_back({1.0, std::sin(phi), cap_end * std::cos(phi)});
    }
    auto add_vertex = [&](const Vec3& p) {
      body.rest.push_back(p);
      std::vector<std::pair<int, double>> row;
      double best = std::numeric_limits<double>::infinity();
      for (int bi : bones)
        best = std::min(best, segment_distance(p, body.skeleton.bone(bi).head, body.skeleton.bone(bi).tail));
      for (int bi : bones) {
        const double dist = segment_distance(p, body.skeleton.bone(bi).head, body.skeleton.bone(bi).tail);
        const double x = (dist - best) / 25.0;  // blend over ~25 mm of distance difference
        const double wgt = std::exp(-x * x * 2.0);
        if (wgt > 0.02) row.emplace_back(bi, wgt);
      }
      rows.push_back(row);
      return static_cast<int>(body.rest.size()) - 1;
    };
    const int first = static_cast<int>(body.rest.size());
    for (const Ring& r : list) {
      const Vec3 c = a + r.s * (b - a) + r.along * d + shift(r.s) * w;
      for (int j = 0; j < segments; ++j) {
        const double t = 2.0 * M_PI * j / segments;
        add_vertex(c + r.scale * (width(r.s) * std::cos(t) * u + depth(r.s) * std::sin(t) * w));
      }
    }
    const int start_pole = add_vertex(a - cap_start * d + shift(0.0) * w);
    const int end_pole = add_vertex(b + cap_end * d + shift(1.0) * w);
    const int n_rings = static_cast<int>(list.size());
    auto at = [&](int ring, int j) { return first + ring * segments + (j % segments); };
    for (int k = 0; k + 1 < n_rings; ++k)
      for (int j = 0; j < segments; ++j)
        body.faces.push_back({at(k, j), at(k, j + 1), at(k + 1, j + 1), at(k + 1, j)});
    for (int j = 0; j < segments; ++j) {
      body.faces.push_back({start_pole, at(0, j + 1), at(0, j), -1});
      body.faces.push_back({end_pole, at(n_rings - 1, j), at(n_rings - 1, j + 1), -1});
    }
  }
};

std::function<double(double)> constant(double v) {
  return [v](double) { return v; };
}
std::function<double(double)> linear(double a, double b) {
  return [a, b](double s) { return a + (b - a) * s; };
}
std::function<double(double)> table(std::vector<double> values) {
  return [values](double s) {
    const double x = std::clamp(s, 0.0, 1.0) * (values.size() - 1);
    const size_t i = std::min(static_cast<size_t>(x), values.size() - 2);
    const double f = x - i;
    return values[i] * (1 - f) + values[i + 1] * f;
  };
}

}  // namespace

Body make_mannequin(int detail) {
  if (detail < 1) throw std::invalid_argument("make_mannequin: detail must be at least 1");
  std::vector<Bone> bones;
  auto index = [&](const std::string& name) {
    for (size_t i = 0; i < bones.size(); ++i)
      if (bones[i].name == name) return static_cast<int>(i);
    return -1;
  };
  for (const BoneDef& def : kBones) {
    const bool is_sided = std::string(def.name).find('*') != std::string::npos;
    for (char side : is_sided ? std::string("LR") : std::string("-")) {
      Bone b;
      b.name = is_sided ? sided(def.name, side) : def.name;
      b.parent = def.parent ? index(is_sided ? sided(def.parent, side) : def.parent) : -1;
      b.head = is_sided ? mirror(def.head, side) : def.head;
      b.tail = is_sided ? mirror(def.tail, side) : def.tail;
      bones.push_back(b);
    }
  }
  Builder m;
  m.body.skeleton = Skeleton(bones);
  const int seg = 16 * detail, ring = 10 * detail;

  m.tube({0, 0, 790}, {0, 0, 1430}, Vec3::UnitX(), 2 * seg, 2 * ring,
         table({150, 160, 135, 140, 155, 165, 140}), table({100, 108, 98, 104, 112, 104, 85}),
         table({0, 5, 15, 25, 30, 20, 5}), 60, 50,
         {"root", "spine05", "spine04", "spine03", "spine02", "spine01", "breast.L", "breast.R", "clavicle.L",
          "clavicle.R", "pelvis.L", "pelvis.R", "upperleg01.L", "upperleg01.R"});
  m.tube({0, 8, 1395}, {0, 20, 1515}, Vec3::UnitX(), seg, ring / 2, constant(55), constant(52), constant(0),
         10, 10, {"spine01", "neck01", "neck02", "neck03", "head"});
  m.tube({0, 15, 1545}, {0, 10, 1660}, Vec3::UnitX(), seg, ring / 2, constant(80), constant(95), constant(10),
         70, 80, {"neck03", "head"});
  for (char side : {'L', 'R'}) {
    auto mv = [side](double x, double y, double z) { return mirror(Vec3(x, y, z), side); };
    auto nm = [side](const char* n) { return sided(n, side); };
    m.tube(mv(-178, 15, 1330), mv(-313, 13, 1166), Vec3::UnitY(), seg, ring, linear(48, 38), linear(48, 38),
           constant(0), 40, 20,
           {nm("shoulder01.*"), nm("upperarm01.*"), nm("upperarm02.*"), nm("lowerarm01.*")});
    m.tube(mv(-313, 13, 1166), mv(-431, 176, 1062), Vec3::UnitZ(), seg, ring, linear(38, 27), linear(38, 27),
           constant(0), 15, 15, {nm("upperarm02.*"), nm("lowerarm01.*"), nm("lowerarm02.*"), nm("wrist.*")});
    m.tube(mv(-431, 176, 1062), mv(-445, 232, 985), Vec3::UnitX(), seg / 2, ring / 2, constant(40),
           constant(15), constant(0), 10, 25, {nm("lowerarm02.*"), nm("wrist.*")});
    m.tube(mv(-108, 20, 845), mv(-158, 32, 448), Vec3::UnitX(), seg, ring, linear(82, 55), linear(82, 55),
           constant(0), 40, 15, {nm("pelvis.*"), nm("upperleg01.*"), nm("upperleg02.*"), nm("lowerleg01.*")});
    m.tube(mv(-158, 32, 448), mv(-220, -1, 72), Vec3::UnitX(), seg, ring, linear(55, 35), linear(55, 35),
           constant(0), 15, 15, {nm("upperleg02.*"), nm("lowerleg01.*"), nm("lowerleg02.*"), nm("foot.*")});
    m.tube(mv(-220, -40, 42), mv(-220, 150, 36), Vec3::UnitX(), seg, ring / 2, linear(38, 34), linear(40, 28),
           constant(0), 20, 20, {nm("lowerleg02.*"), nm("foot.*")});
  }
  m.body.weights = SkinWeights::from_lists(m.rows, m.body.skeleton.size());
  double min_z = std::numeric_limits<double>::infinity();
  for (const Vec3& p : m.body.rest) min_z = std::min(min_z, p.z());
  // Soles at z = 0: shift surface and skeleton together.
  for (Vec3& p : m.body.rest) p.z() -= min_z;
  std::vector<Bone> shifted = m.body.skeleton.bones();
  for (Bone& b : shifted) {
    b.head.z() -= min_z;
    b.tail.z() -= min_z;
  }
  m.body.skeleton = Skeleton(shifted);
  validate(m.body);
  return m.body;
}

}  // namespace skinstream::synth
