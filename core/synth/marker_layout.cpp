#include "core/synth/marker_layout.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <queue>
#include <stdexcept>

#include "core/synth/random.h"

namespace skinstream::synth {

namespace {

bool starts_with(const std::string& s, const char* prefix) { return s.rfind(prefix, 0) == 0; }

// 'L', 'R' or 0 from a MakeHuman bone name.
char bone_side(const std::string& name) {
  if (name.size() > 2 && name[name.size() - 2] == '.') {
    const char c = name.back();
    if (c == 'L' || c == 'R') return c;
  }
  return 0;
}

enum class Coverage { kNone, kTrunk, kProximal, kDistal };

Coverage coverage(const std::string& bone) {
  if (starts_with(bone, "spine") || bone == "root" || starts_with(bone, "pelvis") ||
      starts_with(bone, "breast") || starts_with(bone, "clavicle") || starts_with(bone, "shoulder"))
    return Coverage::kTrunk;
  if (starts_with(bone, "upperarm") || starts_with(bone, "upperleg")) return Coverage::kProximal;
  if (starts_with(bone, "lowerarm") || starts_with(bone, "lowerleg")) return Coverage::kDistal;
  return Coverage::kNone;
}

struct Graph {
  std::vector<int> offsets;
  std::vector<int> targets;
  std::vector<double> lengths;
};

Graph edge_graph(const std::vector<Vec3>& rest, const std::vector<Triangle>& triangles) {
  std::vector<std::vector<int>> adj(rest.size());
  for (const Triangle& t : triangles)
    for (int i = 0; i < 3; ++i) {
      const int a = t[static_cast<size_t>(i)], b = t[static_cast<size_t>((i + 1) % 3)];
      adj[static_cast<size_t>(a)].push_back(b);
      adj[static_cast<size_t>(b)].push_back(a);
    }
  Graph g;
  g.offsets.push_back(0);
  for (size_t v = 0; v < adj.size(); ++v) {
    auto& row = adj[v];
    std::sort(row.begin(), row.end());
    row.erase(std::unique(row.begin(), row.end()), row.end());
    for (int w : row) {
      g.targets.push_back(w);
      g.lengths.push_back((rest[v] - rest[static_cast<size_t>(w)]).norm());
    }
    g.offsets.push_back(static_cast<int>(g.targets.size()));
  }
  return g;
}

// Lowers dist[] with the geodesic distances from `source` (multi-source Dijkstra, incremental).
void relax_from(const Graph& g, int source, std::vector<double>& dist) {
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
  dist[static_cast<size_t>(source)] = 0.0;
  queue.emplace(0.0, source);
  while (!queue.empty()) {
    const auto [d, v] = queue.top();
    queue.pop();
    if (d > dist[static_cast<size_t>(v)]) continue;
    for (int k = g.offsets[static_cast<size_t>(v)]; k < g.offsets[static_cast<size_t>(v) + 1]; ++k) {
      const int w = g.targets[static_cast<size_t>(k)];
      const double nd = d + g.lengths[static_cast<size_t>(k)];
      if (nd < dist[static_cast<size_t>(w)]) {
        dist[static_cast<size_t>(w)] = nd;
        queue.emplace(nd, w);
      }
    }
  }
}

// The candidate vertex near `joint` (within radius) that goes furthest along `direction`.
int extreme_vertex(const std::vector<Vec3>& rest, const std::vector<char>& allowed, const Vec3& joint,
                   double radius, const Vec3& direction) {
  int best = -1;
  double best_score = -std::numeric_limits<double>::infinity();
  for (size_t v = 0; v < rest.size(); ++v) {
    if (!allowed[v]) continue;
    const Vec3 d = rest[v] - joint;
    if (d.norm() > radius) continue;
    const double s = d.dot(direction);
    if (s > best_score) {
      best_score = s;
      best = static_cast<int>(v);
    }
  }
  return best;
}

}  // namespace

std::string marker_region(const Skeleton& skeleton, const Anatomy& anatomy, int dominant_bone, const Vec3& p,
                          const Vec3& n) {
  if (dominant_bone < 0 || dominant_bone >= skeleton.size()) return "body";
  const std::string& bone = skeleton.bone(dominant_bone).name;
  char side = bone_side(bone);
  if (!side) side = p.x() < 0.0 ? 'L' : 'R';
  const std::string suffix = std::string("_") + side;
  const int s = side == 'L' ? kLeft : kRight;
  const bool front = n.dot(kAxisForward) >= -0.1;
  if (bone == "root" || starts_with(bone, "pelvis")) return front ? "pelvis" : "buttock" + suffix;
  if (bone == "spine05" || bone == "spine04" || bone == "spine03") return front ? "abdomen" : "lowerback";
  if (bone == "spine02" || bone == "spine01" || starts_with(bone, "breast"))
    return front ? "chest" : "upperback";
  if (starts_with(bone, "clavicle") || starts_with(bone, "shoulder")) return "shoulder" + suffix;
  if (starts_with(bone, "upperarm") || starts_with(bone, "lowerarm")) {
    if ((p - anatomy.elbow_joint[static_cast<size_t>(s)]).norm() < 60.0) return "elbow" + suffix;
    return (starts_with(bone, "upperarm") ? "upperarm" : "forearm") + suffix;
  }
  if (starts_with(bone, "upperleg")) {
    if ((p - anatomy.knee_joint[static_cast<size_t>(s)]).norm() < 80.0) return "knee" + suffix;
    if (n.dot(kAxisForward) < -0.3 && p.z() > anatomy.hip_joint[static_cast<size_t>(s)].z() - 130.0)
      return "buttock" + suffix;
    return "thigh" + suffix;
  }
  if (starts_with(bone, "lowerleg")) {
    if ((p - anatomy.knee_joint[static_cast<size_t>(s)]).norm() < 80.0) return "knee" + suffix;
    return (front ? "shin" : "calf") + suffix;
  }
  if (starts_with(bone, "neck")) return "neck";
  if (starts_with(bone, "wrist") || starts_with(bone, "finger") || starts_with(bone, "metacarpal"))
    return "hand" + suffix;
  if (starts_with(bone, "foot") || starts_with(bone, "toe")) return "foot" + suffix;
  return "head";
}

std::vector<MarkerSite> layout_markers(const std::vector<Vec3>& rest, const std::vector<Triangle>& triangles,
                                       const SkinWeights& weights, const Skeleton& skeleton,
                                       const Anatomy& anatomy, const LayoutOptions& options, uint64_t seed) {
  const int extras_wanted = 2 * (std::max(0, options.elbow_extras) + std::max(0, options.scapula_extras));
  if (options.count < extras_wanted + 1)
    throw std::invalid_argument("layout_markers: " + std::to_string(options.count) +
                                " markers cannot hold the " + std::to_string(extras_wanted) +
                                " elbow and shoulder-blade markers plus a grid");
  if (weights.vertex_count() != static_cast<int>(rest.size()))
    throw std::invalid_argument("layout_markers: weights and vertices differ in count");
  if (options.elbow_extras > 3 || options.scapula_extras > 2)
    throw std::invalid_argument("layout_markers: at most 3 elbow and 2 shoulder-blade markers per side");
  Random rng = Random::stream(seed, 0x1A70u);

  const size_t n = rest.size();
  const std::vector<Vec3> normals = vertex_normals(rest, triangles);
  std::vector<double> spacing(n, 0.0);  // 0 = not a candidate
  std::vector<char> allowed(n, 0), in_triangle(n, 0);
  for (const Triangle& t : triangles)
    for (int v : t) in_triangle[static_cast<size_t>(v)] = 1;
  int candidates = 0;
  for (size_t v = 0; v < n; ++v) {
    if (!in_triangle[v]) continue;
    const Coverage c = coverage(skeleton.bone(weights.dominant(static_cast<int>(v))).name);
    if (c == Coverage::kNone) continue;
    spacing[v] = c == Coverage::kDistal  ? options.distal_spacing
                 : c == Coverage::kTrunk ? options.trunk_spacing
                                         : 1.0;
    allowed[v] = 1;
    ++candidates;
  }
  if (options.count > candidates)
    throw std::invalid_argument("layout_markers: " + std::to_string(options.count) + " markers but only " +
                                std::to_string(candidates) + " candidate vertices");

  // Extra markers: elbow tips and shoulder blades (vertex, region, extra index).
  struct Seed {
    int vertex;
    std::string region;
  };
  std::vector<Seed> seeds;
  for (Side s : {kLeft, kRight}) {
    const std::string suffix = std::string("_") + side_suffix(s);
    const Vec3 apex = (anatomy.upperarm_dir[s] - anatomy.forearm_dir[s]).normalized();
    const Vec3 hinge = anatomy.elbow_axis[s];
    // The tip of the elbow, then points about 28 mm from it on either side along the hinge.
    const int tip =
        options.elbow_extras > 0 ? extreme_vertex(rest, allowed, anatomy.elbow_joint[s], 75.0, apex) : -1;
    if (tip >= 0) {
      seeds.push_back({tip, "elbow" + suffix});
      for (int k = 1; k < options.elbow_extras; ++k) {
        const Vec3 dir = (k == 1 ? 1.0 : -1.0) * hinge;
        int best = -1;
        double best_score = -std::numeric_limits<double>::infinity();
        for (size_t v = 0; v < n; ++v) {
          if (!allowed[v]) continue;
          const Vec3 d = rest[v] - rest[static_cast<size_t>(tip)];
          const double len = d.norm();
          if (len < 22.0 || len > 34.0) continue;
          const double score = d.dot(dir) / len;
          if (score > best_score) best_score = score, best = static_cast<int>(v);
        }
        if (best >= 0) seeds.push_back({best, "elbow" + suffix});
      }
    }
    const Vec3 sh = anatomy.shoulder_joint[s];
    const Vec3 targets[2] = {Vec3(0.6 * sh.x(), 0.0, sh.z() - 170.0),
                             Vec3(0.42 * sh.x(), 0.0, sh.z() - 70.0)};
    for (int k = 0; k < options.scapula_extras; ++k) {
      int best = -1;
      double best_d = std::numeric_limits<double>::infinity();
      for (size_t v = 0; v < n; ++v) {
        if (!allowed[v] || normals[v].dot(-kAxisForward) < 0.6) continue;
        const double d = std::hypot(rest[v].x() - targets[k].x(), rest[v].z() - targets[k].z());
        if (d < best_d) best_d = d, best = static_cast<int>(v);
      }
      if (best >= 0) seeds.push_back({best, "scapula" + suffix});
    }
  }

  // Farthest-point sampling by geodesic distance, weighted by the local spacing.
  const Graph graph = edge_graph(rest, triangles);
  std::vector<double> dist(n, std::numeric_limits<double>::infinity());
  std::vector<double> jitter(n);
  for (size_t v = 0; v < n; ++v) jitter[v] = 1.0 + options.jitter * rng.uniform();
  std::vector<int> chosen;
  std::vector<char> is_extra;
  for (const Seed& s : seeds) {
    if (dist[static_cast<size_t>(s.vertex)] == 0.0) continue;  // two extras on one vertex
    chosen.push_back(s.vertex);
    is_extra.push_back(1);
    relax_from(graph, s.vertex, dist);
  }
  if (chosen.empty()) {
    std::vector<int> pool;
    for (size_t v = 0; v < n; ++v)
      if (allowed[v]) pool.push_back(static_cast<int>(v));
    const int v = pool[static_cast<size_t>(rng.below(static_cast<int>(pool.size())))];
    chosen.push_back(v);
    is_extra.push_back(0);
    relax_from(graph, v, dist);
  }
  while (static_cast<int>(chosen.size()) < options.count) {
    int best = -1;
    double best_score = -1.0;
    for (size_t v = 0; v < n; ++v) {
      if (!allowed[v]) continue;
      double d = dist[v];
      if (!std::isfinite(d)) d = 1e9;  // an unreached component
      const double score = d / spacing[v] * jitter[v];
      if (score > best_score) best_score = score, best = static_cast<int>(v);
    }
    if (best < 0 || best_score <= 0.0) break;
    chosen.push_back(best);
    is_extra.push_back(0);
    relax_from(graph, best, dist);
  }

  // Put each marker on a triangle around its vertex, a few millimetres off the vertex.
  std::vector<std::vector<int>> incident(n);
  for (size_t t = 0; t < triangles.size(); ++t)
    for (int v : triangles[t]) incident[static_cast<size_t>(v)].push_back(static_cast<int>(t));
  std::vector<MarkerSite> sites;
  std::map<std::string, int> per_region;
  size_t seed_index = 0;
  for (size_t i = 0; i < chosen.size(); ++i) {
    const int v = chosen[i];
    const auto& tris = incident[static_cast<size_t>(v)];
    const int t = tris[static_cast<size_t>(rng.below(static_cast<int>(tris.size())))];
    const Triangle& tri = triangles[static_cast<size_t>(t)];
    const double u1 = rng.uniform(0.0, 0.25), u2 = rng.uniform(0.0, 0.25);
    Vec3 bary;
    for (int k = 0; k < 3; ++k) bary[k] = 0.0;
    int own = 0;
    while (tri[static_cast<size_t>(own)] != v) ++own;
    bary[own] = 1.0 - u1 - u2;
    bary[(own + 1) % 3] = u1;
    bary[(own + 2) % 3] = u2;
    MarkerSite m;
    m.triangle = t;
    m.barycentric = bary;
    const Vec3& a = rest[static_cast<size_t>(tri[0])];
    const Vec3& b = rest[static_cast<size_t>(tri[1])];
    const Vec3& c = rest[static_cast<size_t>(tri[2])];
    m.rest_position = bary[0] * a + bary[1] * b + bary[2] * c;
    m.rest_normal = triangle_normal(a, b, c);
    m.dominant_bone = weights.dominant(v);  // the grid vertex's: the region it was sampled for
    m.extra = is_extra[i] != 0;
    if (m.extra) {
      while (seed_index < seeds.size() && seeds[seed_index].vertex != v) ++seed_index;
      m.region = seed_index < seeds.size() ? seeds[seed_index].region : "extra";
    } else {
      m.region =
          marker_region(skeleton, anatomy, m.dominant_bone, m.rest_position, normals[static_cast<size_t>(v)]);
    }
    sites.push_back(std::move(m));
  }

  // Number within each region from the top down (then left to right, back to front).
  std::vector<size_t> order(sites.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    const MarkerSite &x = sites[a], &y = sites[b];
    if (x.region != y.region) return x.region < y.region;
    if (x.extra != y.extra) return x.extra;
    if (std::abs(x.rest_position.z() - y.rest_position.z()) > 1e-9)
      return x.rest_position.z() > y.rest_position.z();
    if (std::abs(x.rest_position.x() - y.rest_position.x()) > 1e-9)
      return x.rest_position.x() < y.rest_position.x();
    return x.rest_position.y() < y.rest_position.y();
  });
  std::vector<MarkerSite> out;
  out.reserve(sites.size());
  for (size_t i : order) {
    MarkerSite m = sites[i];
    m.name = m.region + "_" + std::to_string(++per_region[m.region]);
    out.push_back(std::move(m));
  }
  return out;
}

}  // namespace skinstream::synth
