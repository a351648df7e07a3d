#include "core/deform/mesh_deformer.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>

#include "core/deform/part_model.h"
#include "core/deform/quadratic_basis.h"

namespace skinstream {

namespace {

// What eq. 8 needs of one part at the solved frame, in float, so the per-vertex work is a few
// small products and one loop over the part's RBF centres that the compiler can vectorise.
struct SolvedPart {
  float quadratic[3][9] = {};         // A_t
  float inverse_rotation[3][3] = {};  // (R_t)^-1 = R_t^T
  float translation[3] = {};          // d_t: world = R_t^T (local - d_t)
  float inverse_sigma = 0.0f;
  bool rbf = false;
  int first_centre = 0;  // into the centre and weight arrays
  int centre_count = 0;
};

// The cubic B-spline of rbf_kernel.h without branches (selects, not std::max). Everything the
// AVX2 clones of rbf_residuals and deform_vertices call is always_inline or a builtin: GCC does
// not inline default-target functions such as std::max or std::sqrt there, and a call in the
// loop stops it vectorising (the loop ran scalar until this was found in the disassembly).
inline __attribute__((always_inline)) float bspline(float r) {
  const float far = r < 2.0f ? 2.0f - r : 0.0f;
  const float near = r < 1.0f ? 1.0f - r : 0.0f;
  return (far * far * far - 4.0f * near * near * near) * (1.0f / 6.0f);
}

// A few influences of one part close together in the reference pose.
struct RbfCluster {
  int part = 0;
  int first = 0;  // into cluster_influences
  int count = 0;
  int64_t rest_cost = 0;  // work at the rest pose: gather test plus the kernel terms kept
};
constexpr int kClusterSize = 32;
// Centres gathered per cluster live on the stack; parts with more members than this are
// evaluated against all their centres instead (never the case for ~350 markers in 17 parts).
constexpr int kMaxGatheredCentres = 1024;

// The quadratic field of eq. 8: A_t q^0 for one influence.
inline __attribute__((always_inline)) void apply_quadratic(const float (&a)[3][9], const float* q, float* out) {
  for (int r = 0; r < 3; ++r) {
    float sum = 0.0f;
    for (int c = 0; c < 9; ++c) sum += a[r][c] * q[c];
    out[r] = sum;
  }
}

// sum_i w_i phi(|x - c_i| / sigma) over n centres (structure of arrays).
inline __attribute__((always_inline)) void sum_rbf(const float* __restrict cx, const float* __restrict cy,
                                                   const float* __restrict cz, const float* __restrict wx,
                                                   const float* __restrict wy, const float* __restrict wz, int n,
                                                   const float* x, float inverse_sigma, float* out) {
  float ox = 0.0f, oy = 0.0f, oz = 0.0f;
  const float x0 = x[0], x1 = x[1], x2 = x[2];
  for (int i = 0; i < n; ++i) {
    const float dx = x0 - cx[i], dy = x1 - cy[i], dz = x2 - cz[i];
    const float phi = bspline(__builtin_sqrtf(dx * dx + dy * dy + dz * dz) * inverse_sigma);
    ox += phi * wx[i];
    oy += phi * wy[i];
    oz += phi * wz[i];
  }
  out[0] = ox;
  out[1] = oy;
  out[2] = oz;
}

// Interleaves the bits of three 10-bit integers: nearby points get nearby codes.
uint32_t morton3(uint32_t x, uint32_t y, uint32_t z) {
  auto spread = [](uint32_t v) {
    v &= 0x3ff;
    v = (v | (v << 16)) & 0x30000ff;
    v = (v | (v << 8)) & 0x300f00f;
    v = (v | (v << 4)) & 0x30c30c3;
    v = (v | (v << 2)) & 0x9249249;
    return v;
  };
  return spread(x) | (spread(y) << 1) | (spread(z) << 2);
}

}  // namespace

struct MeshDeformer::State {
  DeformationMode mode = DeformationMode::QuadraticRbf;
  int marker_count = 0;
  int vertex_count = 0;
  std::vector<std::array<int, 3>> faces;

  std::vector<PartDeformer> parts;
  std::vector<int> member_offsets;  // CSR over parts into member_markers
  std::vector<int> member_markers;
  std::vector<Vec3> member_scratch;

  // Per vertex influence (parallel to the model's vertex_influences): part, beta and the
  // vertex's quadratic vector q^0 in that part's local reference frame (constant, so
  // precomputed: eq. 8 then needs only A_t q^0 per frame).
  std::vector<int> influence_offsets;
  std::vector<int> influence_part;
  std::vector<float> influence_weight;
  std::vector<float> influence_quadratic;  // 9 per influence, of the point clamped to the part's box
  std::vector<float> influence_outside;    // 3 per influence: offset beyond the box (carried rigidly)

  std::vector<SolvedPart> solved;
  std::vector<float> centre_x, centre_y, centre_z, weight_x, weight_y, weight_z;

  // The RBF term of eq. 8 is evaluated per cluster of nearby influences of one part (sorted
  // along a Morton curve of their reference positions): per frame the cluster's deformed
  // bounding sphere selects the centres whose kernel can be non-zero for any of its members
  // (the B-spline vanishes beyond 2 sigma), exactly, without bounds on how the field stretches.
  std::vector<RbfCluster> clusters;
  std::vector<int> cluster_influences;  // influence indices, cluster by cluster
  std::vector<float> rbf_offset;        // 3 per influence: this frame's RBF term, local frame
  std::vector<int64_t> cumulative_cluster_cost;

  // Normals: area-weighted face normals gathered per vertex through a vertex -> face CSR, so
  // vertex ranges can run on different threads without write conflicts.
  std::vector<float> face_normal;  // 3 per face
  std::vector<int> vertex_face_offsets;
  std::vector<int> vertex_faces;

  std::vector<int64_t> cumulative_cost;  // per vertex, for balanced_vertex_split

  void store_solved(int p);
  void build_rbf_clusters(const std::vector<Vec3>& influence_local);
  void deform_vertex(int v, float* out) const;
  void rbf_cluster(int c);
};

MeshDeformer::MeshDeformer(const DeformationModel& model, const SubjectModel& subject, DeformationMode mode)
    : state_(std::make_unique<State>()) {
  const std::string problem = model.validate(subject.marker_count());
  if (!problem.empty()) throw std::invalid_argument(problem);
  State& s = *state_;
  s.mode = mode;
  s.marker_count = subject.marker_count();
  s.vertex_count = model.vertex_count();
  s.faces = model.faces;

  // Parts: the local part reference frames and the offline factors of eqs. 6-7, from the member
  // markers' reference positions (the reference pose is every part's rest state).
  const int part_count = model.part_count();
  s.member_offsets = model.part_member_offsets;
  s.parts.reserve(static_cast<size_t>(part_count));
  s.solved.resize(static_cast<size_t>(part_count));
  size_t largest = 0;
  for (int p = 0; p < part_count; ++p) {
    std::vector<Vec3> reference;
    for (int k = model.part_member_offsets[p]; k < model.part_member_offsets[p + 1]; ++k) {
      const int marker = model.part_members[k].marker;
      s.member_markers.push_back(marker);
      reference.push_back(subject.reference_positions[marker]);
    }
    largest = std::max(largest, reference.size());
    s.solved[p].first_centre = s.member_offsets[p];
    s.solved[p].centre_count = static_cast<int>(reference.size());
    s.parts.emplace_back(build_part_model(reference), mode);
  }
  s.member_scratch.resize(largest);
  const size_t centres = s.member_markers.size();
  for (auto* array : {&s.centre_x, &s.centre_y, &s.centre_z, &s.weight_x, &s.weight_y, &s.weight_z})
    array->assign(centres, 0.0f);

  s.influence_offsets = model.vertex_influence_offsets;
  const size_t influences = model.vertex_influences.size();
  std::vector<Vec3> influence_local(influences);
  s.influence_part.resize(influences);
  s.influence_weight.resize(influences);
  s.influence_quadratic.resize(influences * 9);
  s.influence_outside.resize(influences * 3);
  for (int v = 0; v < s.vertex_count; ++v) {
    for (int k = model.vertex_influence_offsets[v]; k < model.vertex_influence_offsets[v + 1]; ++k) {
      const PartInfluence& inf = model.vertex_influences[k];
      s.influence_part[k] = inf.part;
      s.influence_weight[k] = static_cast<float>(inf.weight);
      const PartModel& part = s.parts[inf.part].model();
      const Vec3 local = part.local_from_world(model.reference_vertices[v]);
      const Vec3 inside = part.clamp_to_bounds(local);
      influence_local[k] = inside;
      const QuadraticVector q = quadratic_basis(inside);
      for (int c = 0; c < 9; ++c) s.influence_quadratic[k * 9 + c] = static_cast<float>(q[c]);
      for (int c = 0; c < 3; ++c) s.influence_outside[k * 3 + c] = static_cast<float>(local[c] - inside[c]);
    }
  }

  s.face_normal.assign(s.faces.size() * 3, 0.0f);
  s.vertex_face_offsets.assign(static_cast<size_t>(s.vertex_count) + 1, 0);
  for (const auto& f : s.faces)
    for (int c : f) ++s.vertex_face_offsets[c + 1];
  for (int v = 0; v < s.vertex_count; ++v) s.vertex_face_offsets[v + 1] += s.vertex_face_offsets[v];
  s.vertex_faces.resize(s.faces.size() * 3);
  std::vector<int> fill(s.vertex_face_offsets.begin(), s.vertex_face_offsets.end() - 1);
  for (size_t f = 0; f < s.faces.size(); ++f)
    for (int c : s.faces[f]) s.vertex_faces[fill[c]++] = static_cast<int>(f);

  for (int p = 0; p < part_count; ++p) s.store_solved(p);  // rest pose until the first solve

  // Work per vertex: the quadratic and rotation of each influence.
  s.cumulative_cost.assign(static_cast<size_t>(s.vertex_count) + 1, 0);
  for (int v = 0; v < s.vertex_count; ++v)
    s.cumulative_cost[v + 1] = s.cumulative_cost[v] + (s.influence_offsets[v + 1] - s.influence_offsets[v]);

  s.rbf_offset.assign(influences * 3, 0.0f);
  if (mode == DeformationMode::RigidRbf || mode == DeformationMode::QuadraticRbf) s.build_rbf_clusters(influence_local);
  s.cumulative_cluster_cost.assign(s.clusters.size() + 1, 0);
  for (size_t c = 0; c < s.clusters.size(); ++c)
    s.cumulative_cluster_cost[c + 1] = s.cumulative_cluster_cost[c] + s.clusters[c].rest_cost;
}

void MeshDeformer::State::build_rbf_clusters(const std::vector<Vec3>& influence_local) {
  std::vector<std::vector<int>> by_part(parts.size());
  for (size_t k = 0; k < influence_part.size(); ++k) by_part[influence_part[k]].push_back(static_cast<int>(k));
  for (size_t p = 0; p < parts.size(); ++p) {
    std::vector<int>& members = by_part[p];
    if (members.empty()) continue;
    const PartModel& model = parts[p].model();
    const Vec3 extent = (model.local_max - model.local_min).cwiseMax(Vec3::Constant(1e-6));
    std::vector<std::pair<uint32_t, int>> keyed;
    keyed.reserve(members.size());
    for (int k : members) {
      const Vec3 unit = (influence_local[k] - model.local_min).cwiseQuotient(extent);
      auto cell = [&](int a) { return static_cast<uint32_t>(std::clamp(unit[a], 0.0, 1.0) * 1023.0); };
      keyed.emplace_back(morton3(cell(0), cell(1), cell(2)), k);
    }
    std::sort(keyed.begin(), keyed.end());
    for (size_t i = 0; i < keyed.size(); i += kClusterSize) {
      RbfCluster cluster;
      cluster.part = static_cast<int>(p);
      cluster.first = static_cast<int>(cluster_influences.size());
      cluster.count = static_cast<int>(std::min<size_t>(kClusterSize, keyed.size() - i));
      Vec3 low = Vec3::Constant(1e30), high = Vec3::Constant(-1e30);
      for (int j = 0; j < cluster.count; ++j) {
        cluster_influences.push_back(keyed[i + j].second);
        low = low.cwiseMin(influence_local[keyed[i + j].second]);
        high = high.cwiseMax(influence_local[keyed[i + j].second]);
      }
      // What rbf_cluster does at the rest pose (A = I): the split by this cost is balanced
      // where the culling removes more terms in big parts than in small ones.
      const double reach = 2.0 * model.rbf_dilation + 0.5 * (high - low).norm();
      int kept = 0;
      for (const Vec3& centre : model.local_reference_points) kept += (centre - 0.5 * (low + high)).norm() < reach;
      cluster.rest_cost = model.member_count() + static_cast<int64_t>(cluster.count) * (16 + (kept + 7) / 8 * 8);
      clusters.push_back(cluster);
    }
  }
}

MeshDeformer::~MeshDeformer() = default;

void MeshDeformer::State::store_solved(int p) {
  const PartDeformer& part = parts[p];
  SolvedPart& out = solved[p];
  const QuadraticTransform& a = part.quadratic_transform();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 9; ++c) out.quadratic[r][c] = static_cast<float>(a(r, c));
  const RigidTransform& to_local = part.to_local();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) out.inverse_rotation[r][c] = static_cast<float>(to_local.rotation(c, r));
    out.translation[r] = static_cast<float>(to_local.translation[r]);
  }
  out.rbf = part.rbf_applied();
  out.inverse_sigma = part.model().rbf_dilation > 0.0 ? static_cast<float>(1.0 / part.model().rbf_dilation) : 0.0f;
  if (!out.rbf) return;
  const Eigen::Matrix3Xd& centres = part.rbf_centres();
  const Eigen::MatrixX3d& weights = part.rbf_weights();
  for (int i = 0; i < out.centre_count; ++i) {
    const int k = out.first_centre + i;
    centre_x[k] = static_cast<float>(centres(0, i));
    centre_y[k] = static_cast<float>(centres(1, i));
    centre_z[k] = static_cast<float>(centres(2, i));
    weight_x[k] = static_cast<float>(weights(i, 0));
    weight_y[k] = static_cast<float>(weights(i, 1));
    weight_z[k] = static_cast<float>(weights(i, 2));
  }
}

bool MeshDeformer::solve_parts(std::span<const Vec3> markers) {
  State& s = *state_;
  if (static_cast<int>(markers.size()) != s.marker_count) return false;
  for (const Vec3& m : markers)
    if (!is_present(m)) return false;
  for (size_t p = 0; p < s.parts.size(); ++p) {
    const int begin = s.member_offsets[p], count = s.member_offsets[p + 1] - begin;
    for (int i = 0; i < count; ++i) s.member_scratch[i] = markers[s.member_markers[begin + i]];
    if (s.parts[p].solve(std::span<const Vec3>(s.member_scratch.data(), count))) s.store_solved(static_cast<int>(p));
  }
  return true;
}

// Eq. 8 in every influencing part (the RBF term from rbf_cluster), blended by eq. 9.
inline __attribute__((always_inline)) void MeshDeformer::State::deform_vertex(int v, float* out) const {
  float result[3] = {0.0f, 0.0f, 0.0f};
  for (int k = influence_offsets[v]; k < influence_offsets[v + 1]; ++k) {
    const SolvedPart& part = solved[influence_part[k]];
    float local[3];
    apply_quadratic(part.quadratic, &influence_quadratic[static_cast<size_t>(k) * 9], local);
    if (part.rbf) {
      const float* rbf = &rbf_offset[static_cast<size_t>(k) * 3];
      local[0] += rbf[0];
      local[1] += rbf[1];
      local[2] += rbf[2];
    }
    const float* outside = &influence_outside[static_cast<size_t>(k) * 3];
    const float lx = local[0] + outside[0] - part.translation[0], ly = local[1] + outside[1] - part.translation[1],
                lz = local[2] + outside[2] - part.translation[2];
    const float beta = influence_weight[k];
    for (int r = 0; r < 3; ++r) {
      const float* row = part.inverse_rotation[r];
      result[r] += beta * (row[0] * lx + row[1] * ly + row[2] * lz);
    }
  }
  out[0] = result[0];
  out[1] = result[1];
  out[2] = result[2];
}

// The RBF term of eq. 8 for one cluster's influences. Centres farther than 2 sigma from every
// deformed influence of the cluster add exactly zero, so only the others are gathered (padded
// with zero weights to whole vectors) and summed.
inline __attribute__((always_inline)) void MeshDeformer::State::rbf_cluster(int c) {
  const RbfCluster& cluster = clusters[c];
  const SolvedPart& part = solved[cluster.part];
  if (!part.rbf) return;  // deform_vertex does not read the offsets then
  float deformed[kClusterSize][3];
  float low[3] = {1e30f, 1e30f, 1e30f}, high[3] = {-1e30f, -1e30f, -1e30f};
  for (int j = 0; j < cluster.count; ++j) {
    const int k = cluster_influences[cluster.first + j];
    apply_quadratic(part.quadratic, &influence_quadratic[static_cast<size_t>(k) * 9], deformed[j]);
    for (int a = 0; a < 3; ++a) {
      low[a] = deformed[j][a] < low[a] ? deformed[j][a] : low[a];
      high[a] = deformed[j][a] > high[a] ? deformed[j][a] : high[a];
    }
  }
  const float* cx = &centre_x[part.first_centre];
  const float* cy = &centre_y[part.first_centre];
  const float* cz = &centre_z[part.first_centre];
  const float* wx = &weight_x[part.first_centre];
  const float* wy = &weight_y[part.first_centre];
  const float* wz = &weight_z[part.first_centre];
  int n = part.centre_count;
  alignas(32) float gx[kMaxGatheredCentres], gy[kMaxGatheredCentres], gz[kMaxGatheredCentres];
  alignas(32) float gwx[kMaxGatheredCentres], gwy[kMaxGatheredCentres], gwz[kMaxGatheredCentres];
  if (n <= kMaxGatheredCentres - 8) {
    const float mid[3] = {0.5f * (low[0] + high[0]), 0.5f * (low[1] + high[1]), 0.5f * (low[2] + high[2])};
    const float hx = 0.5f * (high[0] - low[0]), hy = 0.5f * (high[1] - low[1]), hz = 0.5f * (high[2] - low[2]);
    // Support 2 sigma plus the box's half diagonal, and a hair for rounding.
    const float reach = (2.0f / part.inverse_sigma + __builtin_sqrtf(hx * hx + hy * hy + hz * hz)) * 1.0001f + 1e-3f;
    int m = 0;
    for (int i = 0; i < n; ++i) {
      const float dx = cx[i] - mid[0], dy = cy[i] - mid[1], dz = cz[i] - mid[2];
      if (dx * dx + dy * dy + dz * dz >= reach * reach) continue;
      gx[m] = cx[i];
      gy[m] = cy[i];
      gz[m] = cz[i];
      gwx[m] = wx[i];
      gwy[m] = wy[i];
      gwz[m] = wz[i];
      ++m;
    }
    for (; m % 8 != 0; ++m) {  // whole vectors: zero weights add nothing
      gx[m] = mid[0];
      gy[m] = mid[1];
      gz[m] = mid[2];
      gwx[m] = gwy[m] = gwz[m] = 0.0f;
    }
    cx = gx, cy = gy, cz = gz, wx = gwx, wy = gwy, wz = gwz, n = m;
  }
  for (int j = 0; j < cluster.count; ++j) {
    const int k = cluster_influences[cluster.first + j];
    sum_rbf(cx, cy, cz, wx, wy, wz, n, deformed[j], part.inverse_sigma, &rbf_offset[static_cast<size_t>(k) * 3]);
  }
}

__attribute__((target_clones("arch=x86-64-v3", "default")))
void MeshDeformer::rbf_residuals(int begin, int end) {
  State& s = *state_;
  end = std::min(end, rbf_cluster_count());
  for (int c = std::max(begin, 0); c < end; ++c) s.rbf_cluster(c);
}

int MeshDeformer::rbf_cluster_count() const { return static_cast<int>(state_->clusters.size()); }

int MeshDeformer::balanced_cluster_split(int index, int parts) const {
  const State& s = *state_;
  if (parts <= 0 || index <= 0) return 0;
  if (index >= parts) return rbf_cluster_count();
  const int64_t target = s.cumulative_cluster_cost.back() * index / parts;
  return static_cast<int>(std::lower_bound(s.cumulative_cluster_cost.begin(), s.cumulative_cluster_cost.end(), target) -
                          s.cumulative_cluster_cost.begin());
}

int MeshDeformer::balanced_vertex_split(int index, int parts) const {
  const State& s = *state_;
  if (parts <= 0 || index <= 0) return 0;
  if (index >= parts) return s.vertex_count;
  const int64_t target = s.cumulative_cost.back() * index / parts;
  return static_cast<int>(std::lower_bound(s.cumulative_cost.begin(), s.cumulative_cost.end(), target) -
                          s.cumulative_cost.begin());
}

// Compiled twice (AVX2 + FMA and the baseline); the loader picks the one the CPU runs. The
// clone is named by ISA level: "arch=haswell" dispatches on the CPU model, so AMD processors
// with AVX2 ran the baseline (measured 1.9x slower on this EPYC).
__attribute__((target_clones("arch=x86-64-v3", "default")))
void MeshDeformer::deform_vertices(int begin, int end, std::span<float> positions) const {
  const State& s = *state_;
  end = std::min(end, s.vertex_count);
  if (positions.size() < static_cast<size_t>(s.vertex_count) * 3) return;
  for (int v = std::max(begin, 0); v < end; ++v) s.deform_vertex(v, &positions[static_cast<size_t>(v) * 3]);
}

void MeshDeformer::face_normals(int begin, int end, std::span<const float> positions) {
  State& s = *state_;
  end = std::min(end, face_count());
  if (positions.size() < static_cast<size_t>(s.vertex_count) * 3) return;
  for (int f = std::max(begin, 0); f < end; ++f) {
    const auto& face = s.faces[f];
    const float* a = &positions[static_cast<size_t>(face[0]) * 3];
    const float* b = &positions[static_cast<size_t>(face[1]) * 3];
    const float* c = &positions[static_cast<size_t>(face[2]) * 3];
    const float e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const float e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    float* n = &s.face_normal[static_cast<size_t>(f) * 3];
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];  // twice the area, so the sum is area-weighted
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
  }
}

void MeshDeformer::vertex_normals(int begin, int end, std::span<float> normals) const {
  const State& s = *state_;
  end = std::min(end, s.vertex_count);
  if (normals.size() < static_cast<size_t>(s.vertex_count) * 3) return;
  for (int v = std::max(begin, 0); v < end; ++v) {
    float n[3] = {0.0f, 0.0f, 0.0f};
    for (int k = s.vertex_face_offsets[v]; k < s.vertex_face_offsets[v + 1]; ++k) {
      const float* fn = &s.face_normal[static_cast<size_t>(s.vertex_faces[k]) * 3];
      n[0] += fn[0];
      n[1] += fn[1];
      n[2] += fn[2];
    }
    const float length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    const float scale = length > 0.0f ? 1.0f / length : 0.0f;
    float* out = &normals[static_cast<size_t>(v) * 3];
    out[0] = n[0] * scale;
    out[1] = n[1] * scale;
    out[2] = n[2] * scale;
  }
}

bool MeshDeformer::deform(std::span<const Vec3> markers, std::span<float> positions, std::span<float> normals) {
  if (!solve_parts(markers)) return false;
  rbf_residuals(0, rbf_cluster_count());
  deform_vertices(0, vertex_count(), positions);
  if (!normals.empty()) {
    face_normals(0, face_count(), positions);
    vertex_normals(0, vertex_count(), normals);
  }
  return true;
}

int MeshDeformer::vertex_count() const { return state_->vertex_count; }
int MeshDeformer::face_count() const { return static_cast<int>(state_->faces.size()); }
DeformationMode MeshDeformer::mode() const { return state_->mode; }

size_t MeshDeformer::memory_bytes() const {
  const State& s = *state_;
  auto bytes = [](const auto& v) { return v.capacity() * sizeof(v[0]); };
  size_t total = sizeof(State) + bytes(s.faces) + bytes(s.member_offsets) + bytes(s.member_markers) +
                 bytes(s.member_scratch) + bytes(s.influence_offsets) + bytes(s.influence_part) +
                 bytes(s.influence_weight) + bytes(s.influence_quadratic) + bytes(s.influence_outside) + bytes(s.solved) + bytes(s.centre_x) * 6 +
                 bytes(s.face_normal) + bytes(s.vertex_face_offsets) + bytes(s.vertex_faces) + bytes(s.clusters) +
                 bytes(s.cluster_influences) + bytes(s.rbf_offset) + bytes(s.cumulative_cluster_cost) + bytes(s.cumulative_cost);
  for (const PartDeformer& part : s.parts) {
    const int y = part.model().member_count();
    // Members' reference data (points, Q0, pseudo-inverse) and the per-frame kernel and LU.
    total += sizeof(PartDeformer) + static_cast<size_t>(y) * (3 + 3 + 9 + 9 + 3 + 3 + 3 + 3) * sizeof(double) +
             2 * static_cast<size_t>(y) * y * sizeof(double);
  }
  return total;
}

}  // namespace skinstream
