#include "core/fitting/marker_set.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <stdexcept>

namespace skinstream {

namespace {

constexpr double kMaxRadiusMm = 500.0;
// Vertex normals at least this far toward +Y count as the front: the dense layout's rule.
constexpr double kFrontMinNormalY = -0.1;

char fold(char c) { return static_cast<char>(std::tolower(static_cast<unsigned char>(c))); }

bool equal_folded(std::string_view a, std::string_view b) {
  return a.size() == b.size() &&
         std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) { return fold(x) == fold(y); });
}

// '*' matches any run of characters (none included); everything else itself, case folded or
// not. Iterative with one backtrack point, so a pattern of many stars stays linear.
bool glob_match(std::string_view pattern, std::string_view text, bool fold_case) {
  size_t p = 0, t = 0, star = std::string_view::npos, resume = 0;
  auto same = [&](char a, char b) { return fold_case ? fold(a) == fold(b) : a == b; };
  while (t < text.size()) {
    if (p < pattern.size() && pattern[p] == '*') {
      star = p++;
      resume = t;
    } else if (p < pattern.size() && same(pattern[p], text[t])) {
      ++p;
      ++t;
    } else if (star != std::string_view::npos) {
      p = star + 1;
      t = ++resume;
    } else {
      return false;
    }
  }
  while (p < pattern.size() && pattern[p] == '*') ++p;
  return p == pattern.size();
}

bool has_glob(std::string_view s) { return s.find('*') != std::string_view::npos; }

// Printable ASCII without spaces; ':' never (it separates a subject prefix), '*' only in globs.
std::string name_problem(std::string_view name, bool glob) {
  if (name.empty()) return "is empty";
  for (char c : name) {
    const auto u = static_cast<unsigned char>(c);
    if (u <= 0x20 || u >= 0x7f) return "holds a space or a character that is not printable ASCII";
    if (c == ':') return "holds ':' (the subject prefix separator)";
    if (c == '*' && !glob) return "holds '*' (only patterns may)";
  }
  return {};
}

bool has_control_character(std::string_view text) {
  return std::any_of(text.begin(), text.end(), [](char c) {
    const auto u = static_cast<unsigned char>(c);
    return u < 0x20 || u == 0x7f;
  });
}

std::string entry_name(const MarkerPlacement& p, size_t index) {
  const std::string& n = p.is_region() ? p.pattern : p.name;
  return "entry " + std::to_string(index + 1) + (n.empty() ? std::string() : " (" + n + ")");
}

[[noreturn]] void fail(const std::string& where, const std::string& what) {
  throw std::invalid_argument(where + ": " + what);
}

void check_point_fields(const MarkerPlacement& p, const std::string& where) {
  if (p.bone.empty()) fail(where, "has no bone");
  if (!(p.along >= 0.0 && p.along <= 1.0))
    fail(where, "along must be in [0, 1] (0 = head joint, 1 = tail joint)");
  if (!is_present(p.direction) || p.direction.norm() < 1e-9)
    fail(where, "direction must be finite and not zero");
}

// The index of the first placement of `set` that names `candidate`: names and aliases first,
// then patterns; -1 when none does.
int find_placement(const MarkerSet& set, std::string_view candidate) {
  for (size_t i = 0; i < set.markers.size(); ++i) {
    const MarkerPlacement& p = set.markers[i];
    if (p.is_region()) continue;
    if (equal_folded(p.name, candidate)) return static_cast<int>(i);
    for (const std::string& a : p.aliases)
      if (equal_folded(a, candidate)) return static_cast<int>(i);
  }
  for (size_t i = 0; i < set.markers.size(); ++i)
    if (set.markers[i].is_region() && glob_match(set.markers[i].pattern, candidate, true))
      return static_cast<int>(i);
  return -1;
}

bool is_unlabelled(std::string_view bare) {
  if (bare.empty()) return true;
  if (bare[0] != '*' || bare.size() == 1) return false;
  return std::all_of(bare.begin() + 1, bare.end(),
                     [](char c) { return std::isdigit(static_cast<unsigned char>(c)); });
}

// The placement that names a label: the bare label, then what follows each '_', longest first.
int label_placement(const MarkerSet& set, std::string_view bare) {
  if (const int i = find_placement(set, bare); i >= 0) return i;
  for (size_t u = bare.find('_'); u != std::string_view::npos; u = bare.find('_', u + 1))
    if (u + 1 < bare.size())
      if (const int i = find_placement(set, bare.substr(u + 1)); i >= 0) return i;
  return -1;
}

}  // namespace

void validate(const MarkerSet& set) {
  const std::string set_name = "marker set '" + set.name + "'";
  if (set.name.empty() || has_control_character(set.name))
    fail("marker set", "needs a name of printable text");
  if (set.source.empty() || has_control_character(set.source))
    fail(set_name, "needs a source (where its names and placements come from) of printable text");
  if (set.markers.empty()) fail(set_name, "has no markers");
  std::vector<std::pair<std::string, std::string>> names;  // (name, where) of every name and alias
  std::vector<std::pair<std::string, std::string>> patterns;
  for (size_t i = 0; i < set.markers.size(); ++i) {
    const MarkerPlacement& p = set.markers[i];
    const std::string where = set_name + " " + entry_name(p, i);
    if (has_control_character(p.description)) fail(where, "description holds a control character");
    if (p.is_region()) {
      if (const std::string problem = name_problem(p.pattern, true); !problem.empty())
        fail(where, "pattern " + problem);
      if (!has_glob(p.pattern))
        fail(where, "pattern has no '*' (a single marker is a point entry with a name)");
      if (!p.name.empty() || !p.aliases.empty() || !p.bone.empty())
        fail(where, "a region entry (pattern) takes bones, not a name, aliases or a bone");
      if (p.bones.empty()) fail(where, "has no bones");
      for (const std::string& b : p.bones)
        if (const std::string problem = name_problem(b, true); !problem.empty())
          fail(where, "bone name " + problem);
      if (p.side != kAnySide && p.side != kFrontSide && p.side != kBackSide)
        fail(where, "side must be front, back or any");
      patterns.emplace_back(p.pattern, where);
      continue;
    }
    if (const std::string problem = name_problem(p.name, false); !problem.empty())
      fail(where, "name " + problem);
    names.emplace_back(p.name, where);
    for (const std::string& a : p.aliases) {
      if (const std::string problem = name_problem(a, false); !problem.empty())
        fail(where, "alias '" + a + "' " + problem);
      names.emplace_back(a, where);
    }
    if (!p.bones.empty() || p.side != kAnySide)
      fail(where, "a point entry (name) takes a bone, not bones or a side");
    check_point_fields(p, where);
    if (const std::string problem = name_problem(p.bone, false); !problem.empty())
      fail(where, "bone " + problem);
    if (!(p.radius_mm > 0.0 && p.radius_mm <= kMaxRadiusMm)) fail(where, "radius_mm must be in (0, 500]");
  }
  for (size_t i = 0; i < names.size(); ++i)
    for (size_t j = 0; j < i; ++j)
      if (equal_folded(names[i].first, names[j].first))
        fail(names[i].second,
             "name '" + names[i].first + "' repeats one of " + names[j].second + " (case ignored)");
  for (size_t i = 0; i < patterns.size(); ++i) {
    for (size_t j = 0; j < i; ++j)
      if (equal_folded(patterns[i].first, patterns[j].first))
        fail(patterns[i].second, "repeats the pattern of " + patterns[j].second);
    for (const auto& [name, where] : names)
      if (glob_match(patterns[i].first, name, true))
        fail(where, "name '" + name + "' is also matched by the pattern of " + patterns[i].second);
  }
}

std::string bare_label(std::string_view label) {
  const size_t colon = label.rfind(':');
  if (colon != std::string_view::npos) label.remove_prefix(colon + 1);
  const auto space = [](char c) { return std::isspace(static_cast<unsigned char>(c)) != 0; };
  while (!label.empty() && space(label.front())) label.remove_prefix(1);
  while (!label.empty() && space(label.back())) label.remove_suffix(1);
  return std::string(label);
}

MarkerSetMatch match_marker_set(std::span<const MarkerSet> sets, std::span<const std::string> labels) {
  std::vector<std::string> bare;
  bare.reserve(labels.size());
  int labelled = 0;
  for (const std::string& l : labels) {
    bare.push_back(bare_label(l));
    if (!is_unlabelled(bare.back())) ++labelled;
  }
  MarkerSetMatch best;
  best.placement.assign(labels.size(), -1);
  best.labelled = labelled;
  for (size_t s = 0; s < sets.size(); ++s) {
    MarkerSetMatch m;
    m.set = static_cast<int>(s);
    m.labelled = labelled;
    m.placement.assign(labels.size(), -1);
    for (size_t l = 0; l < labels.size(); ++l) {
      if (is_unlabelled(bare[l])) continue;
      m.placement[l] = label_placement(sets[s], bare[l]);
      if (m.placement[l] >= 0) ++m.matched;
    }
    if (m.matched == 0) continue;
    const bool better = m.matched > best.matched ||
                        (m.matched == best.matched &&
                         sets[s].markers.size() < sets[static_cast<size_t>(best.set)].markers.size());
    if (better) best = std::move(m);
  }
  return best;
}

std::string describe_match(std::span<const MarkerSet> sets, std::span<const std::string> labels,
                           const MarkerSetMatch& match) {
  const std::string counts =
      std::to_string(match.matched) + " of " + std::to_string(match.labelled) + " labelled markers";
  if (match.set < 0 || match.set >= static_cast<int>(sets.size()))
    return "no known marker set names any of the " + std::to_string(match.labelled) + " labelled markers";
  const std::string set_name = sets[static_cast<size_t>(match.set)].name;
  if (match.known()) return set_name + ": " + counts + " named";
  std::string line = "no known marker set (the best, " + set_name + ", names " + counts + "); unnamed:";
  int listed = 0;
  for (size_t l = 0; l < labels.size() && l < match.placement.size(); ++l) {
    const std::string bare = bare_label(labels[l]);
    if (match.placement[l] >= 0 || is_unlabelled(bare)) continue;
    if (++listed > 8) {
      line += " ...";
      break;
    }
    line += " " + bare;
  }
  return line;
}

SurfacePoint place_marker(const Body& body, std::span<const Triangle> triangles, const TriangleBvh& bvh,
                          const MarkerPlacement& placement) {
  const std::string where = "marker " + placement.name;
  if (placement.is_region()) fail("region " + placement.pattern, "has no single site to place");
  check_point_fields(placement, where);
  const int bone = body.skeleton.find(placement.bone);
  if (bone < 0) fail(where, "bone " + placement.bone + " is not in the skeleton");
  const Bone& b = body.skeleton.bone(bone);
  const Vec3 origin = b.head + placement.along * (b.tail - b.head);
  const Vec3 direction = placement.direction.normalized();
  for (const RayHit& hit : bvh.ray_hits(origin, direction)) {
    if (hit.triangle < 0 || hit.triangle >= static_cast<int>(triangles.size()))
      fail(where, "the search structure does not match the triangles");
    const Triangle& t = triangles[static_cast<size_t>(hit.triangle)];
    for (int v : t)
      if (v < 0 || v >= body.vertex_count()) fail(where, "a triangle's vertex is not in the body");
    const Vec3 &a = body.rest[static_cast<size_t>(t[0])], &c1 = body.rest[static_cast<size_t>(t[1])],
               &c2 = body.rest[static_cast<size_t>(t[2])];
    const Vec3 n = triangle_normal(a, c1, c2);
    if (n.dot(direction) <= 0.0) continue;  // an entry (or edge-on): the exit lies beyond
    SurfacePoint s;
    s.triangle = hit.triangle;
    s.barycentric = hit.barycentric;
    s.position = hit.barycentric[0] * a + hit.barycentric[1] * c1 + hit.barycentric[2] * c2;
    s.normal = n;
    return s;
  }
  fail(where, "the ray from bone " + placement.bone + " never leaves the body");
}

std::vector<char> region_triangles(const Body& body, std::span<const Triangle> triangles,
                                   const MarkerPlacement& placement) {
  if (!placement.is_region()) fail("marker " + placement.name, "is a point entry, not a region");
  const std::string where = "region " + placement.pattern;
  if (body.weights.vertex_count() != body.vertex_count())
    fail(where, "the body's weights are not one row per vertex");
  std::vector<char> bone_in(static_cast<size_t>(body.skeleton.size()), 0);
  for (const std::string& name : placement.bones) {
    bool found = false;
    for (int b = 0; b < body.skeleton.size(); ++b)
      if (glob_match(name, body.skeleton.bone(b).name, false)) bone_in[static_cast<size_t>(b)] = found = true;
    if (!found) fail(where, "bone " + name + " is not in the skeleton");
  }
  const std::vector<Triangle> tris(triangles.begin(), triangles.end());
  for (const Triangle& t : tris)
    for (int v : t)
      if (v < 0 || v >= body.vertex_count()) fail(where, "a triangle's vertex is not in the body");
  const std::vector<Vec3> normals = vertex_normals(body.rest, tris);
  std::vector<char> vertex_in(static_cast<size_t>(body.vertex_count()), 0);
  for (int v = 0; v < body.vertex_count(); ++v) {
    if (!bone_in[static_cast<size_t>(body.weights.dominant(v))]) continue;
    const double ny = normals[static_cast<size_t>(v)].y();
    if (placement.side == kFrontSide && ny < kFrontMinNormalY) continue;
    if (placement.side == kBackSide && ny >= kFrontMinNormalY) continue;
    vertex_in[static_cast<size_t>(v)] = 1;
  }
  std::vector<char> in(tris.size(), 0);
  for (size_t t = 0; t < tris.size(); ++t)
    for (int v : tris[t]) in[t] = static_cast<char>(in[t] || vertex_in[static_cast<size_t>(v)]);
  return in;
}

}  // namespace skinstream
