#include "core/deform/mesh_deformer.h"

#include <algorithm>
#include <cmath>
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

// The cubic B-spline of rbf_kernel.h without branches: max() clamps both pieces to zero.
inline float bspline(float r) {
  const float far = std::max(2.0f - r, 0.0f);
  const float near = std::max(1.0f - r, 0.0f);
  return (far * far * far - 4.0f * near * near * near) * (1.0f / 6.0f);
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

  // Normals: area-weighted face normals gathered per vertex through a vertex -> face CSR, so
  // vertex ranges can run on different threads without write conflicts.
  std::vector<float> face_normal;  // 3 per face
  std::vector<int> vertex_face_offsets;
  std::vector<int> vertex_faces;

  std::vector<int64_t> cumulative_cost;  // per vertex, for balanced_vertex_split

  void store_solved(int p);
  void deform_vertex(int v, float* out) const;
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

  // Work per vertex: the quadratic and rotation, plus one kernel term per RBF centre.
  const bool rbf = mode == DeformationMode::RigidRbf || mode == DeformationMode::QuadraticRbf;
  s.cumulative_cost.assign(static_cast<size_t>(s.vertex_count) + 1, 0);
  for (int v = 0; v < s.vertex_count; ++v) {
    int64_t cost = 0;
    for (int k = s.influence_offsets[v]; k < s.influence_offsets[v + 1]; ++k)
      cost += 16 + (rbf ? s.solved[s.influence_part[k]].centre_count : 0);
    s.cumulative_cost[v + 1] = s.cumulative_cost[v] + cost;
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

// Eq. 8 in every influencing part, blended by eq. 9.
inline __attribute__((always_inline)) void MeshDeformer::State::deform_vertex(int v, float* out) const {
  float result[3] = {0.0f, 0.0f, 0.0f};
  for (int k = influence_offsets[v]; k < influence_offsets[v + 1]; ++k) {
    const SolvedPart& part = solved[influence_part[k]];
    const float* q = &influence_quadratic[static_cast<size_t>(k) * 9];
    float local[3];
    for (int r = 0; r < 3; ++r) {
      float sum = 0.0f;
      for (int c = 0; c < 9; ++c) sum += part.quadratic[r][c] * q[c];
      local[r] = sum;
    }
    if (part.rbf) {
      float ox = 0.0f, oy = 0.0f, oz = 0.0f;
      const int first = part.first_centre, last = first + part.centre_count;
#pragma omp simd reduction(+ : ox, oy, oz)
      for (int i = first; i < last; ++i) {
        const float dx = local[0] - centre_x[i], dy = local[1] - centre_y[i], dz = local[2] - centre_z[i];
        const float phi = bspline(std::sqrt(dx * dx + dy * dy + dz * dz) * part.inverse_sigma);
        ox += phi * weight_x[i];
        oy += phi * weight_y[i];
        oz += phi * weight_z[i];
      }
      local[0] += ox;
      local[1] += oy;
      local[2] += oz;
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

int MeshDeformer::balanced_vertex_split(int index, int parts) const {
  const State& s = *state_;
  if (parts <= 0 || index <= 0) return 0;
  if (index >= parts) return s.vertex_count;
  const int64_t target = s.cumulative_cost.back() * index / parts;
  return static_cast<int>(std::lower_bound(s.cumulative_cost.begin(), s.cumulative_cost.end(), target) -
                          s.cumulative_cost.begin());
}

// Compiled twice (AVX2 + FMA and the baseline); the loader picks the one the CPU runs.
__attribute__((target_clones("arch=haswell", "default")))
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
                 bytes(s.face_normal) + bytes(s.vertex_face_offsets) + bytes(s.vertex_faces);
  for (const PartDeformer& part : s.parts) {
    const int y = part.model().member_count();
    // Members' reference data (points, Q0, pseudo-inverse) and the per-frame kernel and LU.
    total += sizeof(PartDeformer) + static_cast<size_t>(y) * (3 + 3 + 9 + 9 + 3 + 3 + 3 + 3) * sizeof(double) +
             2 * static_cast<size_t>(y) * y * sizeof(double);
  }
  return total;
}

}  // namespace skinstream
