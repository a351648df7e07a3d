#include "core/deform/mesh_evaluator.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "core/deform/lane_vectors.h"
#include "core/deform/quadratic_terms.h"

namespace skinstream {

namespace {

using namespace simd;

// Returning a vector type: only in this file, which is compiled with -Wno-psabi (the tests
// including lane_vectors.h are not).
inline __attribute__((always_inline)) Lanes load_lanes(const float* from) {
  Lanes lanes;
  __builtin_memcpy(&lanes, from, sizeof(Lanes));
  return lanes;
}

inline __attribute__((always_inline)) Lanes lane_sqrt(const Lanes& x) {
  Lanes r;
  for (int l = 0; l < kLanes; ++l) r[l] = __builtin_sqrtf(x[l]);  // one vsqrtps per register
  return r;
}

// The unit area-weighted normals of one block of the normals' fans (see State::normal_rows and
// vertex_normals), x y z _ per segment. Exactly: rows read with 3-float loads (the block reads
// the buffer's last point); a template argument, so that the loop has no branch.
template <bool kExactly>
inline __attribute__((always_inline)) void block_normals(const float* __restrict p, const int* __restrict rows,
                                                         int row_count, Lanes& unit) {
  auto load = [p](const int* row, Lanes& points) __attribute__((always_inline)) {
    if constexpr (kExactly)
      load_quads_exactly(p, row, points);
    else
      load_quads(p, row, points);
  };
  Lanes centre, a, a_rotated;
  load(rows, centre);
  load(rows + kQuadsPerLanes, a);
  a -= centre;
  rotate_xyz(a, a_rotated);
  Lanes plus = {}, minus = {};  // two sums: two independent multiply-add chains
  for (int k = 2; k < row_count; ++k) {
    Lanes b, b_rotated;
    load(rows + static_cast<size_t>(k) * kQuadsPerLanes, b);
    b -= centre;
    rotate_xyz(b, b_rotated);
    plus += a * b_rotated;  // twice the face's area: area-weighted
    minus += a_rotated * b;
    a = b, a_rotated = b_rotated;
  }
  Lanes n, squared_yzx, squared_zxy;
  rotate_xyz(plus - minus, n);
  const Lanes squared = n * n;
  rotate_xyz(squared, squared_yzx);
  rotate_xyz(squared_yzx, squared_zxy);
  // 1 / |n| in x, y and z of each segment. A zero normal stays zero: the smallest normal float
  // keeps the root finite, and is far below the squared area of any face of a mesh in mm (a
  // comparison and select here was compiled to sixteen scalar compares).
  unit = n * ((Lanes{} + 1.0f) / lane_sqrt(squared + squared_yzx + squared_zxy + __FLT_MIN__));
}

// What eq. 8 needs of one part at the solved frame, in float: the cluster stage broadcasts
// these scalars over its vector lanes.
struct SolvedPart {
  float quadratic[3][9] = {};         // A_t
  float inverse_rotation[3][3] = {};  // (R_t)^-1 = R_t^T
  float translation[3] = {};          // d_t: world = R_t^T (local - d_t)
  float inverse_sigma = 0.0f;
  bool rbf = false;
  int first_centre = 0;  // into the centre and weight arrays
  int centre_count = 0;
};

// A few influences of one part close together in the reference pose, all of vertices in the
// lower or all in the upper half of the vertex sequence (see State::window_sequence).
struct InfluenceCluster {
  int part = 0;
  int count = 0;  // lanes in use; the others copy lane 0 with beta 0
  bool upper_half = false;
};
// 64 against 32: about 3% faster on one thread and on two (the cull of the part's centres is
// shared by four lane blocks instead of two; the box it culls with grows a little).
constexpr int kClusterSize = 64;
// Vertex normals are computed in blocks of kQuadsPerLanes vertices formed within windows of
// this many consecutive vertices (see State::normal_rows).
constexpr int kNormalWindow = 64;
// The indices of the centres near a cluster live on the stack; parts with more members than
// this are culled and summed in several passes (never the case for ~350 markers in 17 parts).
constexpr int kMaxGatheredCentres = 1024;

// One RBF centre this frame, in the units deform_cluster sums in (see set_part): what the
// kernel sum reads of a centre shares one half cache line.
struct alignas(32) RbfCentre {
  float x = 0, y = 0, z = 0;     // position in units of sigma
  float wx = 0, wy = 0, wz = 0;  // weight over 6
  float unused[2] = {};
};

// A cluster's constant data, structure of arrays over its lanes (one influence per lane).
struct alignas(64) ClusterLanes {
  // The point clamped to the part's box, in the part's local frame: its q^0 is formed per frame
  // (six multiplies per lane), half the bytes of storing all nine terms (at 120 Hz the frame
  // reads this from memory, not from cache).
  float inside[3][kClusterSize];
  float outside[3][kClusterSize];  // offset beyond the box (carried rigidly)
  float beta[kClusterSize];        // the vertex's weight for the part (eq. 9)
};
// A cluster's result this frame: beta * eq. 8 per lane, world frame, x then y then z.
struct alignas(64) ClusterResult {
  float xyz[3][kClusterSize];
};
static_assert(sizeof(ClusterResult) == 3 * kClusterSize * sizeof(float), "results are indexed as one float array");

// Adds 6 * sum_i w_i phi(|x - c_i|) for kLanes points x at once over the n centres listed, all
// in units of sigma (set_part folded 1/sigma into x and c and 1/6 into w). Vectorised over
// points, not centres: each centre is broadcast and the sums stay in registers, with no
// horizontal adds.
inline __attribute__((always_inline)) void sum_rbf_lanes(const RbfCentre* __restrict centres,
                                                         const int* __restrict listed, int n, Lanes x, Lanes y,
                                                         Lanes z, Lanes& sx, Lanes& sy, Lanes& sz) {
  const Lanes zero = {};
  for (int i = 0; i < n; ++i) {
    const RbfCentre& c = centres[listed[i]];
    const Lanes dx = x - c.x, dy = y - c.y, dz = z - c.z;
    const Lanes squared = dx * dx + dy * dy + dz * dz;
    const Lanes r = lane_sqrt(squared);
    // 6 phi: (2 - r)^3 on [1, 2), 4 - 6 r^2 + 3 r^3 below 1 (two fused multiply-adds), 0 beyond.
    const Lanes far = 2.0f - r;
    const Lanes outer = r < 2.0f ? far * far * far : zero;
    const Lanes inner = (3.0f * r - 6.0f) * squared + 4.0f;
    const Lanes phi = r < 1.0f ? inner : outer;
    sx += phi * c.wx;
    sy += phi * c.wy;
    sz += phi * c.wz;
  }
}

// Above every Morton code (30 bits): the sort key of a cluster influence of the upper half.
constexpr uint32_t kUpperHalfKey = 1u << 30;

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

struct MeshEvaluator::State {
  int vertex_count = 0;
  int part_count = 0;
  std::vector<float> member_reference;  // p^0, 3 per member (the model's)
  std::vector<float> part_sigma;

  // The order the vertex stages count vertices in (their "slots"): whole windows of
  // kNormalWindow consecutive vertices, sorted by their centroid along the coordinate axis that
  // cuts the fewest mesh edges at the middle slot, the short last window (if any) last. Cut in
  // two at half_slot, the sequence is two spatially compact halves of the body, each touching
  // the other only along the cut; DeformWorkers gives one to each thread, which then blends and
  // computes the normals of vertices whose neighbours it blended itself. The windows keep the
  // output buffers' cache lines whole: no line is written by both halves.
  std::vector<int> window_sequence;  // per position in the sequence, the window (vertex / kNormalWindow)
  int half_slot = 0;                 // the first slot of the upper half (a window boundary)

  std::vector<SolvedPart> solved;
  // Per part (from SolvedPart::first_centre) its RBF centres and weights this frame.
  std::vector<RbfCentre> centres;

  // Eq. 8 is evaluated per cluster of up to kClusterSize influences (vertex, part) of one part
  // that lie close together in the reference pose (sorted along a Morton curve), and of
  // vertices from one half of the vertex sequence (see window_sequence): the quadratic
  // field in vector lanes, and for the RBF term the cluster's deformed bounding box selects the
  // centres whose kernel can be non-zero for any of its members (the B-spline vanishes beyond
  // 2 sigma), exactly, without bounds on how the field stretches.
  std::vector<InfluenceCluster> clusters;
  std::vector<ClusterLanes> cluster_lanes;    // parallel to clusters
  std::vector<ClusterResult> cluster_result;  // parallel to clusters
  // Eq. 9: per slot of the sequence (CSR) where the vertex's influences' results are:
  // cluster * 3 * kClusterSize + lane, as a float index into cluster_result. In sequence order,
  // so that a range of slots reads these as one stream.
  std::vector<int> influence_offsets;
  std::vector<int> influence_results;

  // Normals: per vertex its neighbours in fan order, n_0, n_1, ..., where each consecutive
  // pair (n_i, n_i+1) closes a face (v, n_i, n_i+1) of the mesh (a closed fan repeats n_0 at
  // the end). The area-weighted normal is then sum (n_i - v) x (n_i+1 - v), one neighbour read
  // per face, from the positions alone: vertex ranges run on different threads without a face
  // pass. Where the faces around v do not form one fan (border, non-manifold), the pieces are
  // separated by v itself, whose offset from v is zero and so adds nothing.
  // Laid out for four vertices at a time, one per 128-bit segment of a Lanes register, each
  // segment holding a point as x y z and one more float (see load_quads): a cross product is then
  // two multiplies and two in-segment rotations, with no transpose. The vertices of a block need
  // not be consecutive (each segment is stored to its own vertex), so blocks are formed inside
  // windows of kNormalWindow consecutive vertices sorted by fan length: a block's fans are then
  // about as long as each other, and padding them to the longest costs little (where vertices of
  // 4 and 8 faces alternate, as in a triangulated quad mesh, consecutive blocks padded 20% of
  // the rows). Block b's rows are normal_rows[4 * normal_block_rows[b] ...], row 0 its own
  // vertices, row k the k-th entry of each lane's fan (a float index, 3 * vertex), padded to the
  // block's longest fan with the lane's own vertex: a zero offset, so the pads add nothing. A
  // window short of four vertices at the end repeats its last one, which is stored twice alike.
  std::vector<int> normal_window_blocks;  // per window of the sequence its first block, and one past the end
  std::vector<int> normal_block_rows;     // per block its first row, and one past the end
  std::vector<int> normal_rows;           // 4 entries per row
  std::vector<uint8_t> normal_block_reads_last;  // per block: it reads the last vertex (load_quads_exactly)

  void build_sequence(const EvaluationModel& model);
  void build_clusters(const EvaluationModel& model);
  void build_fans(const std::vector<std::array<int, 3>>& faces);
  void deform_cluster(int c);
};

MeshEvaluator::MeshEvaluator(const EvaluationModel& model) : state_(std::make_unique<State>()) {
  const std::string problem = model.validate();
  if (!problem.empty()) throw std::invalid_argument(problem);
  State& s = *state_;
  s.vertex_count = model.vertex_count();
  s.part_count = model.part_count();
  s.member_reference = model.member_reference;
  s.solved.resize(static_cast<size_t>(s.part_count));
  for (int p = 0, first = 0; p < s.part_count; first += model.parts[p].member_count, ++p) {
    s.solved[p].first_centre = first;
    s.solved[p].centre_count = model.parts[p].member_count;
    s.part_sigma.push_back(model.parts[p].sigma);
  }
  s.centres.assign(static_cast<size_t>(model.member_count()), RbfCentre{});

  s.build_sequence(model);
  s.build_clusters(model);
  s.build_fans(model.faces);

  set_parameters(rest_parameters(model));
  for (int c = 0; c < static_cast<int>(s.clusters.size()); ++c) s.deform_cluster(c);
}

MeshEvaluator::~MeshEvaluator() = default;

void MeshEvaluator::State::build_sequence(const EvaluationModel& model) {
  const int windows = (vertex_count + kNormalWindow - 1) / kNormalWindow;
  const int full_windows = vertex_count / kNormalWindow;
  half_slot = full_windows / 2 * kNormalWindow;
  std::vector<int> best;
  long best_cut = -1;
  std::vector<int> order(static_cast<size_t>(full_windows)), position(static_cast<size_t>(windows));
  std::vector<double> centroid(static_cast<size_t>(full_windows));
  for (int axis = 0; axis < 3; ++axis) {
    for (int w = 0; w < full_windows; ++w) {
      double sum = 0.0;
      for (int v = w * kNormalWindow; v < (w + 1) * kNormalWindow; ++v) sum += model.reference_vertices[3 * static_cast<size_t>(v) + axis];
      centroid[w] = sum;
    }
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return centroid[a] < centroid[b]; });
    if (windows > full_windows) order.push_back(full_windows);  // the short window, last
    for (int i = 0; i < windows; ++i) position[order[i]] = i;
    auto upper = [&](int v) { return position[v / kNormalWindow] * kNormalWindow >= half_slot; };
    long cut = 0;
    for (const auto& f : model.faces)
      for (int c = 0; c < 3; ++c) cut += upper(f[c]) != upper(f[(c + 1) % 3]);
    if (best_cut < 0 || cut < best_cut) best_cut = cut, best = order;
    order.resize(static_cast<size_t>(full_windows));
  }
  window_sequence = best;
}

void MeshEvaluator::State::build_clusters(const EvaluationModel& model) {
  std::vector<std::vector<int>> by_part(static_cast<size_t>(part_count));
  for (int k = 0; k < model.influence_count(); ++k) by_part[model.influence_parts[k]].push_back(k);
  std::vector<int> vertex_of(static_cast<size_t>(model.influence_count()));
  for (int v = 0; v < vertex_count; ++v)
    for (int k = model.influence_offsets[v]; k < model.influence_offsets[v + 1]; ++k) vertex_of[k] = v;
  std::vector<int> result_of(static_cast<size_t>(model.influence_count()), 0);  // per influence of the model
  std::vector<int> window_position(window_sequence.size());  // inverse of window_sequence
  for (size_t i = 0; i < window_sequence.size(); ++i) window_position[window_sequence[i]] = static_cast<int>(i);
  auto in_upper_half = [&](int v) { return window_position[v / kNormalWindow] * kNormalWindow >= half_slot; };
  for (int p = 0; p < part_count; ++p) {
    const EvaluationPart& part = model.parts[p];
    // u = R^0 v^0 + d^0, in double from the model's floats (the same on every machine that
    // evaluates this model), and s = u clamped to the members' box.
    auto local_of = [&](int v) {
      double u[3];
      for (int r = 0; r < 3; ++r) {
        u[r] = part.translation[r];
        for (int c = 0; c < 3; ++c) u[r] += double(part.rotation[3 * r + c]) * model.reference_vertices[3 * static_cast<size_t>(v) + c];
      }
      return std::array<double, 3>{u[0], u[1], u[2]};
    };
    const size_t n = by_part[p].size();
    std::vector<std::array<double, 3>> local(n), inside(n);
    std::vector<std::pair<uint32_t, int>> keyed;  // Morton code of the clamped point, index into by_part
    for (size_t i = 0; i < n; ++i) {
      const int v = vertex_of[by_part[p][i]];
      local[i] = local_of(v);
      uint32_t cell[3];
      for (int a = 0; a < 3; ++a) {
        inside[i][a] = std::clamp(local[i][a], double(part.box_min[a]), double(part.box_max[a]));
        const double extent = std::max(double(part.box_max[a]) - part.box_min[a], 1e-6);
        cell[a] = static_cast<uint32_t>(std::clamp((inside[i][a] - part.box_min[a]) / extent, 0.0, 1.0) * 1023.0);
      }
      keyed.emplace_back((in_upper_half(v) ? kUpperHalfKey : 0u) | morton3(cell[0], cell[1], cell[2]), static_cast<int>(i));
    }
    // The lower half of the sequence first, then the upper; each along the Morton curve.
    std::sort(keyed.begin(), keyed.end());
    const auto upper_begin = std::partition_point(keyed.begin(), keyed.end(), [](const auto& k) { return k.first < kUpperHalfKey; });
    const size_t halves[3] = {0, static_cast<size_t>(upper_begin - keyed.begin()), keyed.size()};
    for (int half = 0; half < 2; ++half) {
      for (size_t first = halves[half]; first < halves[half + 1]; first += kClusterSize) {
        InfluenceCluster cluster;
        cluster.part = p;
        cluster.count = static_cast<int>(std::min<size_t>(kClusterSize, halves[half + 1] - first));
        cluster.upper_half = half == 1;
        ClusterLanes lanes{};
        for (int lane = 0; lane < kClusterSize; ++lane) {
          const int i = keyed[first + (lane < cluster.count ? lane : 0)].second;
          const int k = by_part[p][i];
          for (int c = 0; c < 3; ++c) lanes.inside[c][lane] = static_cast<float>(inside[i][c]);
          for (int c = 0; c < 3; ++c) lanes.outside[c][lane] = static_cast<float>(local[i][c] - inside[i][c]);
          if (lane >= cluster.count) continue;
          lanes.beta[lane] = model.influence_weights[k];
          result_of[k] = static_cast<int>(clusters.size()) * 3 * kClusterSize + lane;
        }
        clusters.push_back(cluster);
        cluster_lanes.push_back(lanes);
      }
    }
  }
  cluster_result.assign(clusters.size(), ClusterResult{});
  clusters.shrink_to_fit();  // grown by push_back: up to half of it slack
  cluster_lanes.shrink_to_fit();

  influence_offsets.assign(1, 0);
  influence_results.clear();
  influence_results.reserve(result_of.size());
  for (int w : window_sequence)
    for (int v = w * kNormalWindow; v < std::min((w + 1) * kNormalWindow, vertex_count); ++v) {
      for (int k = model.influence_offsets[v]; k < model.influence_offsets[v + 1]; ++k) influence_results.push_back(result_of[k]);
      influence_offsets.push_back(static_cast<int>(influence_results.size()));
    }
}

void MeshEvaluator::State::build_fans(const std::vector<std::array<int, 3>>& faces) {
  // Per vertex the (b, c) corner pairs of its faces, in each face's winding.
  std::vector<int> pair_offsets(static_cast<size_t>(vertex_count) + 1, 0);
  for (const auto& f : faces)
    for (int c : f) ++pair_offsets[c + 1];
  for (int v = 0; v < vertex_count; ++v) pair_offsets[v + 1] += pair_offsets[v];
  std::vector<std::array<int, 2>> pairs(faces.size() * 3);
  std::vector<int> fill(pair_offsets.begin(), pair_offsets.end() - 1);
  for (const auto& f : faces)
    for (int corner = 0; corner < 3; ++corner) pairs[fill[f[corner]]++] = {f[(corner + 1) % 3], f[(corner + 2) % 3]};

  std::vector<int> fan_offsets(static_cast<size_t>(vertex_count) + 1, 0);
  std::vector<int> fans;
  std::vector<char> used;
  for (int v = 0; v < vertex_count; ++v) {
    const int first = pair_offsets[v], count = pair_offsets[v + 1] - first;
    used.assign(static_cast<size_t>(count), 0);
    for (int left = count; left > 0;) {
      // Start where no other unused pair ends (a border), else anywhere (a closed fan).
      int start = -1;
      for (int i = 0; i < count && start < 0; ++i) {
        if (used[i]) continue;
        bool continues_another = false;
        for (int j = 0; j < count; ++j) continues_another |= !used[j] && j != i && pairs[first + j][1] == pairs[first + i][0];
        if (!continues_another) start = i;
      }
      for (int i = 0; i < count && start < 0; ++i)
        if (!used[i]) start = i;
      if (fans.size() > static_cast<size_t>(fan_offsets[v])) fans.push_back(v);  // separates pieces
      fans.push_back(pairs[first + start][0]);
      for (int i = start; i >= 0;) {
        used[i] = 1;
        --left;
        fans.push_back(pairs[first + i][1]);
        const int reached = pairs[first + i][1];
        i = -1;
        for (int j = 0; j < count && i < 0; ++j)
          if (!used[j] && pairs[first + j][0] == reached) i = j;
      }
    }
    fan_offsets[v + 1] = static_cast<int>(fans.size());
  }

  normal_window_blocks.assign(1, 0);
  normal_block_rows.assign(1, 0);
  normal_rows.clear();
  normal_block_reads_last.clear();
  std::vector<int> order;
  auto fan_length = [&](int v) { return fan_offsets[v + 1] - fan_offsets[v]; };
  for (int w : window_sequence) {  // in sequence order: a range of slots reads one stream of rows
    const int first = w * kNormalWindow, last = std::min(first + kNormalWindow, vertex_count);
    order.resize(static_cast<size_t>(last - first));
    std::iota(order.begin(), order.end(), first);
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return fan_length(a) < fan_length(b); });
    for (size_t q = 0; q < order.size(); q += kQuadsPerLanes) {
      int lane_vertex[kQuadsPerLanes];
      int rows = 0;
      for (int l = 0; l < kQuadsPerLanes; ++l) {
        lane_vertex[l] = order[std::min(q + l, order.size() - 1)];
        rows = std::max(rows, fan_length(lane_vertex[l]));
      }
      // block_normals reads two rows at least: four vertices in no face get a row of themselves
      // (a zero normal).
      rows = std::max(rows, 1);
      bool reads_last = false;
      for (int k = -1; k < rows; ++k)  // -1: the block's own vertices
        for (int v : lane_vertex) {
          const int read = k < 0 ? v : (k < fan_length(v) ? fans[fan_offsets[v] + k] : v);
          normal_rows.push_back(3 * read);
          reads_last |= read == vertex_count - 1;
        }
      normal_block_reads_last.push_back(reads_last);
      normal_block_rows.push_back(normal_block_rows.back() + rows + 1);
    }
    normal_window_blocks.push_back(static_cast<int>(normal_block_rows.size()) - 1);
  }
  normal_rows.shrink_to_fit();
  normal_block_rows.shrink_to_fit();
  normal_block_reads_last.shrink_to_fit();
}

void MeshEvaluator::set_part(int p, const PartParameters& in, std::span<const float> weights) {
  State& s = *state_;
  SolvedPart& out = s.solved[p];
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 9; ++c) out.quadratic[r][c] = in.quadratic[9 * r + c];
    for (int c = 0; c < 3; ++c) out.inverse_rotation[r][c] = in.rotation[3 * c + r];  // R_t^T
    out.translation[r] = in.translation[r];
  }
  const float sigma = s.part_sigma[p];
  out.inverse_sigma = sigma > 0.0f ? 1.0f / sigma : 0.0f;
  out.rbf = in.rbf && sigma > 0.0f && weights.size() >= 3 * static_cast<size_t>(out.centre_count);
  if (!out.rbf) return;
  for (int i = 0; i < out.centre_count; ++i) {
    // The centre p~_i = A_t q(p^0_i), formed from the floats every evaluator of this frame has.
    const float* p0 = &s.member_reference[3 * static_cast<size_t>(out.first_centre + i)];
    double q[9];
    quadratic_terms(double(p0[0]), double(p0[1]), double(p0[2]), q);
    double centre[3];
    for (int r = 0; r < 3; ++r) {
      centre[r] = 0.0;
      for (int k = 0; k < 9; ++k) centre[r] += double(in.quadratic[9 * r + k]) * q[k];
    }
    RbfCentre& c = s.centres[out.first_centre + i];
    // In the units deform_cluster sums in: centres in sigma, weights over 6 (the B-spline's).
    c.x = static_cast<float>(centre[0] * out.inverse_sigma);
    c.y = static_cast<float>(centre[1] * out.inverse_sigma);
    c.z = static_cast<float>(centre[2] * out.inverse_sigma);
    c.wx = weights[3 * i] / 6.0f;
    c.wy = weights[3 * i + 1] / 6.0f;
    c.wz = weights[3 * i + 2] / 6.0f;
  }
}

bool MeshEvaluator::set_parameters(const FrameParameters& parameters) {
  const State& s = *state_;
  if (static_cast<int>(parameters.parts.size()) != s.part_count || parameters.weights.size() != s.member_reference.size()) return false;
  for (const PartParameters& part : parameters.parts)
    for (float v : part.quadratic) if (!std::isfinite(v)) return false;
  for (const PartParameters& part : parameters.parts) {
    for (float v : part.rotation) if (!std::isfinite(v)) return false;
    for (float v : part.translation) if (!std::isfinite(v)) return false;
  }
  for (float w : parameters.weights) if (!std::isfinite(w)) return false;
  for (int p = 0; p < s.part_count; ++p)
    set_part(p, parameters.parts[p], std::span(parameters.weights).subspan(3 * static_cast<size_t>(s.solved[p].first_centre)));
  return true;
}

// Eq. 8 for one cluster's influences, times their beta: the quadratic field A_t q^0, the RBF
// term, then back to the world frame. Centres farther than 2 sigma from every deformed
// influence of the cluster add exactly zero to the RBF term, so only the others are gathered.
inline __attribute__((always_inline)) void MeshEvaluator::State::deform_cluster(int c) {
  static_assert(kClusterSize % kLanes == 0);
  constexpr int kBlocks = kClusterSize / kLanes;
  const InfluenceCluster& cluster = clusters[c];
  const SolvedPart& part = solved[cluster.part];
  const ClusterLanes& in = cluster_lanes[c];
  Lanes local[kBlocks][3];
  for (int b = 0; b < kBlocks; ++b) {
    const Lanes x = load_lanes(in.inside[0] + b * kLanes), y = load_lanes(in.inside[1] + b * kLanes),
                z = load_lanes(in.inside[2] + b * kLanes);
    Lanes q[9];
    quadratic_terms(x, y, z, q);
    for (int r = 0; r < 3; ++r) {
      Lanes sum = part.quadratic[r][0] * q[0];
      for (int k = 1; k < 9; ++k) sum += part.quadratic[r][k] * q[k];
      local[b][r] = sum;
    }
  }
  if (part.rbf) {
    // The deformed influences in units of sigma, and their bounding box (the unused lanes
    // repeat lane 0, so every lane may take part).
    const float inverse_sigma = part.inverse_sigma;
    Lanes scaled[kBlocks][3];
    float low[3], high[3];
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b < kBlocks; ++b) scaled[b][a] = local[b][a] * inverse_sigma;
      Lanes lowest = scaled[0][a], highest = scaled[0][a];
      for (int b = 1; b < kBlocks; ++b) {
        lowest = scaled[b][a] < lowest ? scaled[b][a] : lowest;
        highest = scaled[b][a] > highest ? scaled[b][a] : highest;
      }
      lane_min(lowest, low[a]);
      lane_max(highest, high[a]);
    }
    const float mid[3] = {0.5f * (low[0] + high[0]), 0.5f * (low[1] + high[1]), 0.5f * (low[2] + high[2])};
    const float hx = 0.5f * (high[0] - low[0]), hy = 0.5f * (high[1] - low[1]), hz = 0.5f * (high[2] - low[2]);
    // Support 2 (sigma units) plus the box's half diagonal, and a hair for rounding.
    const float reach = (2.0f + __builtin_sqrtf(hx * hx + hy * hy + hz * hz)) * 1.0001f + 1e-3f;
    const float reach_squared = reach * reach;
    const RbfCentre* __restrict all = centres.data();
    alignas(64) int listed[kMaxGatheredCentres];
    const int end = part.first_centre + part.centre_count;
    for (int i = part.first_centre; i < end;) {  // one pass unless a part has more centres than the stack holds
      // Without a branch: about half the centres pass, in no order a predictor could learn (in
      // perf the version with a branch spent about a quarter of the cluster stage in this loop).
      int m = 0;
      for (; i < end && m < kMaxGatheredCentres; ++i) {
        const float dx = all[i].x - mid[0], dy = all[i].y - mid[1], dz = all[i].z - mid[2];
        listed[m] = i;
        m += dx * dx + dy * dy + dz * dz < reach_squared;
      }
      for (int b = 0; b < kBlocks; ++b)
        sum_rbf_lanes(all, listed, m, scaled[b][0], scaled[b][1], scaled[b][2], local[b][0], local[b][1], local[b][2]);
    }
  }
  ClusterResult& out = cluster_result[c];
  for (int b = 0; b < kBlocks; ++b) {
    Lanes shifted[3];
    for (int a = 0; a < 3; ++a) shifted[a] = local[b][a] + load_lanes(in.outside[a] + b * kLanes) - part.translation[a];
    const Lanes beta = load_lanes(in.beta + b * kLanes);
    for (int r = 0; r < 3; ++r) {
      const float* row = part.inverse_rotation[r];
      const Lanes world = row[0] * shifted[0] + row[1] * shifted[1] + row[2] * shifted[2];
      const Lanes weighted = beta * world;
      __builtin_memcpy(out.xyz[r] + b * kLanes, &weighted, sizeof(Lanes));
    }
  }
}

// Compiled three times (AVX-512, AVX2 + FMA, baseline); the loader picks what the CPU runs.
// The clones are named by ISA level: "arch=haswell" dispatches on the CPU model, so AMD
// processors with AVX2 ran the baseline (measured 1.9x slower on this EPYC). Not under
// ThreadSanitizer: the clones' resolver is instrumented and runs while the loader relocates,
// before the sanitizer's runtime exists, and the program crashed before main.
#if defined(__SANITIZE_THREAD__)
#define SKINSTREAM_ISA_CLONES
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define SKINSTREAM_ISA_CLONES
#endif
#endif
#ifndef SKINSTREAM_ISA_CLONES
#define SKINSTREAM_ISA_CLONES __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#endif
SKINSTREAM_ISA_CLONES
void MeshEvaluator::deform_clusters(int begin, int end) {
  State& s = *state_;
  end = std::min(end, cluster_count());
  for (int c = std::max(begin, 0); c < end; ++c) s.deform_cluster(c);
}

int MeshEvaluator::cluster_count() const { return static_cast<int>(state_->clusters.size()); }

void MeshEvaluator::blend_vertices(int begin, int end, std::span<float> positions) const {
  const State& s = *state_;
  end = std::min(end, s.vertex_count);
  begin = std::max(begin, 0);
  if (positions.size() < static_cast<size_t>(s.vertex_count) * 3 || begin >= end) return;
  const float* results = s.cluster_result.empty() ? nullptr : s.cluster_result.front().xyz[0];
  for (int at = begin; at < end;) {  // window by window of the sequence
    const int in_window = at % kNormalWindow, count = std::min(end - at, kNormalWindow - in_window);
    const int first = s.window_sequence[at / kNormalWindow] * kNormalWindow + in_window;
    for (int v = first, slot = at; v < first + count; ++v, ++slot) {
      float sum[3] = {0.0f, 0.0f, 0.0f};
      for (int k = s.influence_offsets[slot]; k < s.influence_offsets[slot + 1]; ++k) {
        const float* result = results + s.influence_results[k];
        sum[0] += result[0];
        sum[1] += result[kClusterSize];
        sum[2] += result[2 * kClusterSize];
      }
      float* out = &positions[static_cast<size_t>(v) * 3];
      out[0] = sum[0], out[1] = sum[1], out[2] = sum[2];
    }
    at += count;
  }
}

// Four vertices at a time, one per 128-bit segment: each row of neighbours is four 4-float
// loads, and the area-weighted sum of (n_i - v) x (n_i+1 - v) is accumulated as
// a * rotated(b) - rotated(a) * b, the cross product with its components rotated, which one
// more rotation per vertex puts right. This replaced sixteen vertices per register with x, y
// and z in separate registers, which needed a transpose of every row loaded and a fan padded
// to the longest of sixteen (see State::normal_rows): the frame's work fell from about 1170 to
// 1070 us on one thread (deform_benchmark's frame_work_p50_us).
// Every vertex goes through the same lane code whatever the range, so a normal does not
// depend on how the vertices were cut into ranges; a range only limits what is written.
SKINSTREAM_ISA_CLONES
void MeshEvaluator::vertex_normals(int begin, int end, std::span<const float> positions, std::span<float> normals) const {
  const State& s = *state_;
  end = std::min(end, s.vertex_count);
  const size_t needed = static_cast<size_t>(s.vertex_count) * 3;
  if (positions.size() < needed || normals.size() < needed) return;
  begin = std::max(begin, 0);
  if (begin >= end) return;
  const float* __restrict p = positions.data();
  float* __restrict out = normals.data();
  for (int at = begin; at < end;) {  // window by window of the sequence
    const int in_window = at % kNormalWindow, count = std::min(end - at, kNormalWindow - in_window);
    const int window = s.window_sequence[at / kNormalWindow];
    // The range's vertices in this window, as float indices (3 * vertex), as the rows hold them.
    const int write_begin = 3 * (window * kNormalWindow + in_window), write_end = write_begin + 3 * count;
    for (int block = s.normal_window_blocks[at / kNormalWindow]; block < s.normal_window_blocks[at / kNormalWindow + 1]; ++block) {
      const int* rows = &s.normal_rows[static_cast<size_t>(s.normal_block_rows[block]) * kQuadsPerLanes];
      const int row_count = s.normal_block_rows[block + 1] - s.normal_block_rows[block];
      Lanes unit;
      if (s.normal_block_reads_last[block])
        block_normals<true>(p, rows, row_count, unit);
      else
        block_normals<false>(p, rows, row_count, unit);
      auto store = [&](auto segment) __attribute__((always_inline)) {
        const int vertex = rows[segment()];
        if (vertex >= write_begin && vertex < write_end) store_xyz<segment()>(unit, out + vertex);
      };
      store(std::integral_constant<int, 0>{});
      store(std::integral_constant<int, 1>{});
      store(std::integral_constant<int, 2>{});
      store(std::integral_constant<int, 3>{});
    }
    at += count;
  }
}

bool MeshEvaluator::evaluate(const FrameParameters& parameters, std::span<float> positions, std::span<float> normals) {
  if (!set_parameters(parameters)) return false;
  deform_clusters(0, cluster_count());
  blend_vertices(0, vertex_count(), positions);
  if (!normals.empty()) vertex_normals(0, vertex_count(), positions, normals);
  return true;
}

int MeshEvaluator::vertex_count() const { return state_->vertex_count; }
int MeshEvaluator::part_count() const { return state_->part_count; }
int MeshEvaluator::cluster_part(int c) const { return state_->clusters[c].part; }
bool MeshEvaluator::cluster_in_upper_half(int c) const { return state_->clusters[c].upper_half; }
int MeshEvaluator::sequence_vertex(int slot) const {
  if (slot < 0 || slot >= state_->vertex_count) throw std::out_of_range("MeshEvaluator::sequence_vertex: no such slot");
  return state_->window_sequence[static_cast<size_t>(slot / kNormalWindow)] * kNormalWindow + slot % kNormalWindow;
}
int MeshEvaluator::upper_half_slot() const { return state_->half_slot; }
int MeshEvaluator::normal_group_size() const { return kNormalWindow; }

size_t MeshEvaluator::memory_bytes() const {
  const State& s = *state_;
  auto bytes = [](const auto& v) { return v.capacity() * sizeof(v[0]); };
  return sizeof(State) + bytes(s.member_reference) + bytes(s.part_sigma) + bytes(s.influence_offsets) +
         bytes(s.influence_results) + bytes(s.solved) + bytes(s.centres) + bytes(s.window_sequence) +
         bytes(s.normal_window_blocks) + bytes(s.normal_block_rows) + bytes(s.normal_rows) + bytes(s.normal_block_reads_last) +
         bytes(s.clusters) + bytes(s.cluster_lanes) + bytes(s.cluster_result);
}

FrameParameters rest_parameters(const EvaluationModel& model) {
  FrameParameters rest;
  rest.resize(model.part_count(), model.member_count());
  for (int p = 0; p < model.part_count(); ++p) {
    PartParameters& part = rest.parts[p];
    for (int r = 0; r < 3; ++r) part.quadratic[9 * r + r] = 1.0f;  // A = [I 0 0]
    part.rotation = model.parts[p].rotation;
    part.translation = model.parts[p].translation;
    part.rbf = false;
  }
  return rest;
}

}  // namespace skinstream
