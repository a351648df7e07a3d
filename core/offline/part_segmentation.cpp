#include "core/offline/part_segmentation.h"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <string>

#include "core/absolute_orientation.h"
#include "core/precondition.h"

namespace skinstream {
namespace {

using Triangles = std::span<const std::array<int, 3>>;

constexpr Precondition require_segmentation{"part segmentation"};

void check_inputs(std::span<const Vec3> reference, Triangles triangles, std::span<const Vec3> positions, int frame_count,
                  int sample_frames) {
  const int m = static_cast<int>(reference.size());
  require_segmentation(m > 0, "no markers");
  require_segmentation(!triangles.empty(), "no triangles");
  require_segmentation(frame_count > 0, "no frames");
  require_segmentation(sample_frames >= 1, "sample_frames must be >= 1");
  require_segmentation(positions.size() == static_cast<size_t>(frame_count) * m,
          std::to_string(positions.size()) + " positions for " + std::to_string(frame_count) + " frames of " +
              std::to_string(m) + " markers");
  for (size_t t = 0; t < triangles.size(); ++t)
    for (int v : triangles[t])
      require_segmentation(v >= 0 && v < m, "triangle " + std::to_string(t) + " refers to marker " + std::to_string(v) + " of " + std::to_string(m));
  for (int i = 0; i < m; ++i) require_segmentation(reference[i].allFinite(), "reference marker " + std::to_string(i) + " is not finite");
  for (size_t k = 0; k < positions.size(); ++k)
    require_segmentation(positions[k].allFinite(), "marker " + std::to_string(k % m) + " is not finite at frame " + std::to_string(k / m));
}

// Evenly spaced frames, first and last included.
std::vector<int> sample_frame_indices(int frame_count, int samples) {
  std::vector<int> out;
  if (samples >= frame_count) {
    for (int f = 0; f < frame_count; ++f) out.push_back(f);
    return out;
  }
  for (int k = 0; k < samples; ++k)
    out.push_back(samples == 1 ? 0 : static_cast<int>(std::lround(static_cast<double>(k) * (frame_count - 1) / (samples - 1))));
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

// [e1 e2 n] of a triangle, n unit: the deformation gradient maps the reference one onto this.
Eigen::Matrix3d triangle_frame(const Vec3& a, const Vec3& b, const Vec3& c) {
  Eigen::Matrix3d f;
  f.col(0) = b - a;
  f.col(1) = c - a;
  const Vec3 n = f.col(0).cross(f.col(1));
  f.col(2) = n.norm() > 0.0 ? Vec3(n.normalized()) : Vec3::Zero();
  return f;
}

Eigen::Matrix3d polar_rotation(const Eigen::Matrix3d& f) {
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(f, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d u = svd.matrixU();
  if ((u * svd.matrixV().transpose()).determinant() < 0.0) u.col(2) *= -1.0;
  return u * svd.matrixV().transpose();
}

// 9 S x T: each column a triangle's flattened rotations, scaled so that the squared Euclidean
// distance of two columns is the mean over frames of the squared Frobenius distance.
Eigen::MatrixXd rotation_sequences(std::span<const Vec3> reference, Triangles triangles, std::span<const Vec3> positions,
                                   const std::vector<int>& frames) {
  const size_t m = reference.size();
  const double scale = 1.0 / std::sqrt(static_cast<double>(frames.size()));
  Eigen::MatrixXd d(9 * frames.size(), triangles.size());
  for (size_t t = 0; t < triangles.size(); ++t) {
    const auto& tri = triangles[t];
    const Eigen::Matrix3d f0 = triangle_frame(reference[tri[0]], reference[tri[1]], reference[tri[2]]);
    const bool degenerate = !(std::abs(f0.determinant()) > 1e-12 * std::pow(f0.norm(), 3));
    const Eigen::Matrix3d f0_inverse = degenerate ? Eigen::Matrix3d::Identity() : Eigen::Matrix3d(f0.inverse());
    for (size_t k = 0; k < frames.size(); ++k) {
      const Vec3* p = &positions[static_cast<size_t>(frames[k]) * m];
      // A degenerate reference triangle has no rotation of its own: it sits at the identity.
      const Eigen::Matrix3d r = degenerate ? Eigen::Matrix3d::Identity()
                                           : polar_rotation(triangle_frame(p[tri[0]], p[tri[1]], p[tri[2]]) * f0_inverse);
      d.block<9, 1>(9 * k, t) = scale * Eigen::Map<const Eigen::Matrix<double, 9, 1>>(r.data());
    }
  }
  return d;
}

// Gaussian mean shift of every column towards its mode; returns the modes. Columns that have
// stopped moving are left out of later iterations.
Eigen::MatrixXd mean_shift(const Eigen::MatrixXd& points, double bandwidth, int max_iterations) {
  Eigen::MatrixXd modes = points;
  const Eigen::VectorXd point_norms = points.colwise().squaredNorm().transpose();
  const double inv_two_h2 = 1.0 / (2.0 * bandwidth * bandwidth);
  std::vector<int> active(points.cols());
  for (Eigen::Index j = 0; j < points.cols(); ++j) active[j] = static_cast<int>(j);
  Eigen::MatrixXd current, w, next;
  for (int it = 0; it < max_iterations && !active.empty(); ++it) {
    current = modes(Eigen::all, active);
    // squared distance (i point, j mode) = |p_i|^2 + |m_j|^2 - 2 p_i . m_j
    w.noalias() = -2.0 * points.transpose() * current;
    w.colwise() += point_norms;
    w.rowwise() += current.colwise().squaredNorm();
    w = (-w.cwiseMax(0.0) * inv_two_h2).array().exp().matrix();
    next.noalias() = points * w;
    next.array().rowwise() /= w.colwise().sum().array();
    std::vector<int> still;
    for (size_t k = 0; k < active.size(); ++k) {
      if ((next.col(k) - current.col(k)).norm() >= 1e-4 * bandwidth) still.push_back(active[k]);
      modes.col(active[k]) = next.col(k);
    }
    active.swap(still);
  }
  return modes;
}

// Triangles sharing a marker.
std::vector<std::vector<int>> triangles_of_markers(Triangles triangles, int marker_count) {
  std::vector<std::vector<int>> out(marker_count);
  for (size_t t = 0; t < triangles.size(); ++t)
    for (int v : triangles[t])
      if (out[v].empty() || out[v].back() != static_cast<int>(t)) out[v].push_back(static_cast<int>(t));
  return out;
}

// Relabels groups into connected pieces (triangles adjacent when they share a marker).
std::vector<int> split_connected(Triangles triangles, const std::vector<std::vector<int>>& by_marker, const std::vector<int>& group) {
  std::vector<int> out(triangles.size(), -1);
  int next = 0;
  std::vector<int> stack;
  for (size_t seed = 0; seed < triangles.size(); ++seed) {
    if (out[seed] >= 0) continue;
    out[seed] = next;
    stack.assign(1, static_cast<int>(seed));
    while (!stack.empty()) {
      const int t = stack.back();
      stack.pop_back();
      for (int v : triangles[t])
        for (int u : by_marker[v])
          if (out[u] < 0 && group[u] == group[t]) {
            out[u] = next;
            stack.push_back(u);
          }
    }
    ++next;
  }
  return out;
}

// RMS over sampled frames and markers of the residual after the best rigid fit from the
// reference pose.
class RigidError {
 public:
  RigidError(std::span<const Vec3> reference, std::span<const Vec3> positions, std::vector<int> frames)
      : reference_(reference), positions_(positions), frames_(std::move(frames)) {}

  double rms(const std::vector<int>& markers) const {
    if (markers.empty()) return 0.0;
    const size_t m = reference_.size();
    source_.resize(markers.size());
    target_.resize(markers.size());
    for (size_t k = 0; k < markers.size(); ++k) source_[k] = reference_[markers[k]];
    double sum = 0.0;
    for (int f : frames_) {
      for (size_t k = 0; k < markers.size(); ++k) target_[k] = positions_[static_cast<size_t>(f) * m + markers[k]];
      RigidTransform rigid;
      fit_rigid(source_, target_, rigid);
      for (size_t k = 0; k < markers.size(); ++k) sum += (rigid.apply(source_[k]) - target_[k]).squaredNorm();
    }
    return std::sqrt(sum / (markers.size() * frames_.size()));
  }

 private:
  std::span<const Vec3> reference_, positions_;
  std::vector<int> frames_;
  mutable std::vector<Vec3> source_, target_;
};

std::vector<int> markers_of(Triangles triangles, const std::vector<int>& tris) {
  std::vector<int> out;
  for (int t : tris) out.insert(out.end(), triangles[t].begin(), triangles[t].end());
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

std::vector<int> merged(const std::vector<int>& a, const std::vector<int>& b) {
  std::vector<int> out;
  std::set_union(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(out));
  return out;
}

// Greedy merging of adjacent groups down to `target` (see the header).
std::vector<int> merge_groups(Triangles triangles, int marker_count, const std::vector<int>& group, int group_count, int target,
                              int tiny, const RigidError& error) {
  std::vector<std::vector<int>> tris(group_count);
  for (size_t t = 0; t < triangles.size(); ++t) tris[group[t]].push_back(static_cast<int>(t));
  std::vector<std::vector<int>> markers(group_count);
  std::vector<std::vector<int>> groups_of_marker(marker_count);
  for (int g = 0; g < group_count; ++g) {
    markers[g] = markers_of(triangles, tris[g]);
    for (int v : markers[g]) groups_of_marker[v].push_back(g);
  }
  // Ward's criterion on the rigid fit: how much the summed squared residual (over markers and
  // sampled frames) grows when a pair is fitted as one body. Plain merged RMS would favour
  // swallowing small groups into large ones last; the growth merges what adds least error.
  auto sse = [&](const std::vector<int>& ms) {
    const double r = error.rms(ms);
    return r * r * static_cast<double>(ms.size());
  };
  std::vector<double> group_sse(group_count);
  for (int g = 0; g < group_count; ++g) group_sse[g] = sse(markers[g]);
  std::map<std::pair<int, int>, double> cost;  // growth of adjacent pairs (a < b)
  int alive = group_count;
  while (alive > target) {
    std::vector<std::pair<int, int>> pairs;
    for (const auto& gs : groups_of_marker)
      for (size_t i = 0; i < gs.size(); ++i)
        for (size_t j = i + 1; j < gs.size(); ++j) pairs.emplace_back(std::min(gs[i], gs[j]), std::max(gs[i], gs[j]));
    std::sort(pairs.begin(), pairs.end());
    pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
    if (pairs.empty()) break;  // separate pieces of surface: nothing left to merge
    // The smallest tiny group that has a neighbour goes first.
    int focus = -1;
    for (const auto& [a, b] : pairs)
      for (int g : {a, b})
        if (static_cast<int>(tris[g].size()) < tiny &&
            (focus < 0 || tris[g].size() < tris[focus].size() || (tris[g].size() == tris[focus].size() && g < focus)))
          focus = g;
    std::pair<int, int> best{-1, -1};
    double best_cost = std::numeric_limits<double>::infinity();
    for (const auto& p : pairs) {
      if (focus >= 0 && p.first != focus && p.second != focus) continue;
      auto it = cost.find(p);
      if (it == cost.end())
        it = cost.emplace(p, sse(merged(markers[p.first], markers[p.second])) - group_sse[p.first] - group_sse[p.second]).first;
      if (it->second < best_cost) {
        best_cost = it->second;
        best = p;
      }
    }
    const auto [a, b] = best;
    tris[a].insert(tris[a].end(), tris[b].begin(), tris[b].end());
    tris[b].clear();
    markers[a] = merged(markers[a], markers[b]);
    markers[b].clear();
    group_sse[a] = sse(markers[a]);
    --alive;
    for (auto& gs : groups_of_marker) {
      std::replace(gs.begin(), gs.end(), b, a);
      std::sort(gs.begin(), gs.end());
      gs.erase(std::unique(gs.begin(), gs.end()), gs.end());
    }
    for (auto it = cost.begin(); it != cost.end();)
      it = (it->first.first == a || it->first.second == a || it->first.first == b || it->first.second == b) ? cost.erase(it)
                                                                                                          : std::next(it);
  }
  std::vector<int> out(triangles.size());
  for (int g = 0; g < group_count; ++g)
    for (int t : tris[g]) out[t] = g;
  return out;
}

// Numbers parts by their lowest triangle and measures them.
PartSegmentation finish(Triangles triangles, std::vector<int> part, const RigidError& error, bool renumber) {
  PartSegmentation out;
  if (renumber) {
    std::map<int, int> id;
    for (int& p : part) p = id.emplace(p, static_cast<int>(id.size())).first->second;
  }
  out.part_count = part.empty() ? 0 : *std::max_element(part.begin(), part.end()) + 1;
  std::vector<std::vector<int>> tris(out.part_count);
  for (size_t t = 0; t < part.size(); ++t) tris[part[t]].push_back(static_cast<int>(t));
  for (const auto& ts : tris) out.part_rigid_rms_mm.push_back(error.rms(markers_of(triangles, ts)));
  out.triangle_part = std::move(part);
  return out;
}

}  // namespace

PartSegmentation segment_parts(std::span<const Vec3> reference, Triangles triangles, std::span<const Vec3> positions,
                               int frame_count, const SegmentationOptions& options) {
  check_inputs(reference, triangles, positions, frame_count, options.sample_frames);
  require_segmentation(options.target_parts >= 1, "target_parts must be >= 1");
  require_segmentation(options.bandwidth_degrees > 0.0 && options.bandwidth_degrees <= 180.0, "bandwidth_degrees must be in (0, 180]");
  require_segmentation(options.max_mean_shift_iterations >= 0, "max_mean_shift_iterations must be >= 0");
  const int m = static_cast<int>(reference.size());
  const std::vector<int> frames = sample_frame_indices(frame_count, options.sample_frames);

  const Eigen::MatrixXd sequences = rotation_sequences(reference, triangles, positions, frames);
  const double bandwidth = 2.0 * std::sqrt(2.0) * std::sin(options.bandwidth_degrees * M_PI / 360.0);
  const Eigen::MatrixXd modes = mean_shift(sequences, bandwidth, options.max_mean_shift_iterations);

  // Triangles whose modes lie within half a bandwidth of a group's first mode join it.
  std::vector<int> group(triangles.size());
  std::vector<int> representative;
  for (Eigen::Index t = 0; t < modes.cols(); ++t) {
    int g = -1;
    for (size_t k = 0; k < representative.size() && g < 0; ++k)
      if ((modes.col(t) - modes.col(representative[k])).norm() < 0.5 * bandwidth) g = static_cast<int>(k);
    if (g < 0) {
      g = static_cast<int>(representative.size());
      representative.push_back(static_cast<int>(t));
    }
    group[t] = g;
  }
  const std::vector<std::vector<int>> by_marker = triangles_of_markers(triangles, m);
  const std::vector<int> connected = split_connected(triangles, by_marker, group);
  const int connected_count = *std::max_element(connected.begin(), connected.end()) + 1;

  const RigidError error(reference, positions, frames);
  PartSegmentation out = finish(
      triangles, merge_groups(triangles, m, connected, connected_count, options.target_parts, options.tiny_part_triangles, error),
      error, true);
  out.mean_shift_groups = static_cast<int>(representative.size());
  out.connected_groups = connected_count;
  return out;
}

PartSegmentation segmentation_from_assignment(std::span<const Vec3> reference, Triangles triangles, std::span<const Vec3> positions,
                                              int frame_count, std::span<const int> assignment, AssignmentKind kind,
                                              int sample_frames) {
  check_inputs(reference, triangles, positions, frame_count, sample_frames);
  const size_t expected = kind == AssignmentKind::PerTriangle ? triangles.size() : reference.size();
  require_segmentation(assignment.size() == expected, std::to_string(assignment.size()) + " part indices for " + std::to_string(expected) +
                                             (kind == AssignmentKind::PerTriangle ? " triangles" : " markers"));
  for (size_t k = 0; k < assignment.size(); ++k) {
    require_segmentation(assignment[k] >= 0, "part index " + std::to_string(assignment[k]) + " at " + std::to_string(k) + " is negative");
    // More parts than triangles cannot all hold one: a typo, not a segmentation.
    require_segmentation(assignment[k] < static_cast<int>(triangles.size()), "part index " + std::to_string(assignment[k]) + " at " +
                                                                     std::to_string(k) + " is beyond the " +
                                                                     std::to_string(triangles.size()) + " triangles");
  }
  std::vector<int> part(triangles.size());
  for (size_t t = 0; t < triangles.size(); ++t) {
    if (kind == AssignmentKind::PerTriangle) {
      part[t] = assignment[t];
      continue;
    }
    const int a = assignment[triangles[t][0]], b = assignment[triangles[t][1]], c = assignment[triangles[t][2]];
    part[t] = (a == b || a == c) ? a : (b == c ? b : std::min({a, b, c}));
  }
  // Parts left with no triangle are dropped; the rest keep their order.
  const int largest = *std::max_element(assignment.begin(), assignment.end());
  std::vector<int> used(largest + 1, 0);
  for (int p : part) used[p] = 1;
  std::vector<int> renumbered(largest + 1, -1), unused;
  for (int p = 0, next = 0; p <= largest; ++p) {
    if (used[p]) renumbered[p] = next++;
    else unused.push_back(p);
  }
  for (int& p : part) p = renumbered[p];
  PartSegmentation out =
      finish(triangles, std::move(part), RigidError(reference, positions, sample_frame_indices(frame_count, sample_frames)), false);
  out.unused_parts = std::move(unused);
  return out;
}

std::vector<int> marker_parts(Triangles triangles, std::span<const int> triangle_part, int marker_count) {
  require_segmentation(triangle_part.size() == triangles.size(), std::to_string(triangle_part.size()) + " part indices for " +
                                                        std::to_string(triangles.size()) + " triangles");
  std::vector<std::map<int, int>> count(marker_count);  // marker -> part -> triangles
  for (size_t t = 0; t < triangles.size(); ++t)
    for (int v : triangles[t]) {
      require_segmentation(v >= 0 && v < marker_count, "triangle " + std::to_string(t) + " refers to marker " + std::to_string(v));
      ++count[v][triangle_part[t]];
    }
  std::vector<int> out(marker_count, -1);
  for (int m = 0; m < marker_count; ++m) {
    int best = 0;
    for (const auto& [part, n] : count[m])  // ascending part index: ties keep the lowest
      if (n > best) {
        best = n;
        out[m] = part;
      }
  }
  return out;
}

}  // namespace skinstream
