#include "core/deform/mesh_deformer.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <stdexcept>
#include <type_traits>

#include "core/deform/lane_vectors.h"
#include "core/deform/part_model.h"
#include "core/deform/quadratic_basis.h"

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

// One RBF centre this frame, in the units deform_cluster sums in (see store_solved): what the
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
// in units of sigma (store_solved folded 1/sigma into x and c and 1/6 into w). Vectorised over
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

struct MeshDeformer::State {
  DeformationMode mode = DeformationMode::QuadraticRbf;
  int marker_count = 0;
  int vertex_count = 0;

  std::vector<PartDeformer> parts;
  std::vector<int> member_offsets;  // CSR over parts into member_markers
  std::vector<int> member_markers;
  std::vector<Vec3> member_scratch;

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

  void build_sequence(const DeformationModel& model);
  void store_solved(int p);
  void build_clusters(const DeformationModel& model);
  void build_fans(const std::vector<std::array<int, 3>>& faces);
  void deform_cluster(int c);
};

MeshDeformer::MeshDeformer(const DeformationModel& model, const SubjectModel& subject, DeformationMode mode)
    : state_(std::make_unique<State>()) {
  const std::string problem = model.validate(subject.marker_count());
  if (!problem.empty()) throw std::invalid_argument(problem);
  State& s = *state_;
  s.mode = mode;
  s.marker_count = subject.marker_count();
  s.vertex_count = model.vertex_count();

  // Parts: the local part reference frames and the offline factors of eqs. 6-7, from the member
  // markers' reference positions (the reference pose is every part's rest state).
  const int part_count = model.part_count();
  s.member_offsets = model.part_member_offsets;
  s.parts.reserve(static_cast<size_t>(part_count));
  s.solved.resize(static_cast<size_t>(part_count));
  for (int p = 0; p < part_count; ++p) {
    std::vector<Vec3> reference;
    for (int k = model.part_member_offsets[p]; k < model.part_member_offsets[p + 1]; ++k) {
      const int marker = model.part_members[k].marker;
      s.member_markers.push_back(marker);
      reference.push_back(subject.reference_positions[marker]);
    }
    s.solved[p].first_centre = s.member_offsets[p];
    s.solved[p].centre_count = static_cast<int>(reference.size());
    PartModel part = build_part_model(reference, model.part_quadratic_ridge.empty() ? 0.0 : model.part_quadratic_ridge[p]);
    if (!model.part_rbf_ridge.empty()) part.rbf_ridge = model.part_rbf_ridge[p];
    s.parts.emplace_back(std::move(part), mode);
  }
  s.member_scratch.resize(s.member_markers.size());
  s.centres.assign(s.member_markers.size(), RbfCentre{});

  s.build_sequence(model);
  s.build_clusters(model);
  s.build_fans(model.faces);

  // The rest pose until the first fit.
  for (int p = 0; p < part_count; ++p) s.store_solved(p);
  for (int c = 0; c < static_cast<int>(s.clusters.size()); ++c) s.deform_cluster(c);
}

void MeshDeformer::State::build_sequence(const DeformationModel& model) {
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
      for (int v = w * kNormalWindow; v < (w + 1) * kNormalWindow; ++v) sum += model.reference_vertices[v][axis];
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

void MeshDeformer::State::build_clusters(const DeformationModel& model) {
  std::vector<std::vector<int>> by_part(parts.size());
  for (size_t k = 0; k < model.vertex_influences.size(); ++k) by_part[model.vertex_influences[k].part].push_back(static_cast<int>(k));
  std::vector<int> vertex_of(model.vertex_influences.size());
  for (int v = 0; v < vertex_count; ++v)
    for (int k = model.vertex_influence_offsets[v]; k < model.vertex_influence_offsets[v + 1]; ++k) vertex_of[k] = v;
  std::vector<int> result_of(model.vertex_influences.size(), 0);  // per influence of the model
  std::vector<int> window_position(window_sequence.size());  // inverse of window_sequence
  for (size_t i = 0; i < window_sequence.size(); ++i) window_position[window_sequence[i]] = static_cast<int>(i);
  auto in_upper_half = [&](int v) { return window_position[v / kNormalWindow] * kNormalWindow >= half_slot; };
  for (size_t p = 0; p < parts.size(); ++p) {
    const PartModel& part = parts[p].model();
    std::vector<Vec3> local(by_part[p].size()), inside(by_part[p].size());
    std::vector<std::pair<uint32_t, int>> keyed;  // Morton code of the clamped point, index into by_part
    const Vec3 extent = (part.local_max - part.local_min).cwiseMax(Vec3::Constant(1e-6));
    for (size_t i = 0; i < by_part[p].size(); ++i) {
      local[i] = part.local_from_world(model.reference_vertices[vertex_of[by_part[p][i]]]);
      inside[i] = part.clamp_to_bounds(local[i]);
      const Vec3 unit = (inside[i] - part.local_min).cwiseQuotient(extent);
      auto cell = [&](int a) { return static_cast<uint32_t>(std::clamp(unit[a], 0.0, 1.0) * 1023.0); };
      const bool upper = in_upper_half(vertex_of[by_part[p][i]]);
      keyed.emplace_back((upper ? kUpperHalfKey : 0u) | morton3(cell(0), cell(1), cell(2)), static_cast<int>(i));
    }
    // The lower half of the sequence first, then the upper; each along the Morton curve.
    std::sort(keyed.begin(), keyed.end());
    const auto upper_begin = std::partition_point(keyed.begin(), keyed.end(), [](const auto& k) { return k.first < kUpperHalfKey; });
    const size_t halves[3] = {0, static_cast<size_t>(upper_begin - keyed.begin()), keyed.size()};
    for (int half = 0; half < 2; ++half) {
      for (size_t first = halves[half]; first < halves[half + 1]; first += kClusterSize) {
        InfluenceCluster cluster;
        cluster.part = static_cast<int>(p);
        cluster.count = static_cast<int>(std::min<size_t>(kClusterSize, halves[half + 1] - first));
        cluster.upper_half = half == 1;
        ClusterLanes lanes{};
        for (int lane = 0; lane < kClusterSize; ++lane) {
          const int i = keyed[first + (lane < cluster.count ? lane : 0)].second;
          const int k = by_part[p][i];
          for (int c = 0; c < 3; ++c) lanes.inside[c][lane] = static_cast<float>(inside[i][c]);
          for (int c = 0; c < 3; ++c) lanes.outside[c][lane] = static_cast<float>(local[i][c] - inside[i][c]);
          if (lane >= cluster.count) continue;
          lanes.beta[lane] = static_cast<float>(model.vertex_influences[k].weight);
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
      for (int k = model.vertex_influence_offsets[v]; k < model.vertex_influence_offsets[v + 1]; ++k)
        influence_results.push_back(result_of[k]);
      influence_offsets.push_back(static_cast<int>(influence_results.size()));
    }
}

void MeshDeformer::State::build_fans(const std::vector<std::array<int, 3>>& faces) {
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
    RbfCentre& c = this->centres[out.first_centre + i];
    // In the units deform_cluster sums in: centres in sigma, weights over 6 (the B-spline's).
    c.x = static_cast<float>(centres(0, i) * out.inverse_sigma);
    c.y = static_cast<float>(centres(1, i) * out.inverse_sigma);
    c.z = static_cast<float>(centres(2, i) * out.inverse_sigma);
    c.wx = static_cast<float>(weights(i, 0) / 6.0);
    c.wy = static_cast<float>(weights(i, 1) / 6.0);
    c.wz = static_cast<float>(weights(i, 2) / 6.0);
  }
}

bool MeshDeformer::accepts(std::span<const Vec3> markers) const {
  if (static_cast<int>(markers.size()) != state_->marker_count) return false;
  for (const Vec3& m : markers)
    if (!is_present(m)) return false;
  return true;
}

void MeshDeformer::solve_part(int p, std::span<const Vec3> markers) {
  State& s = *state_;
  const int begin = s.member_offsets[p], count = s.member_offsets[p + 1] - begin;
  Vec3* members = s.member_scratch.data() + begin;  // each part its own slice: parts may run in parallel
  for (int i = 0; i < count; ++i) members[i] = markers[s.member_markers[begin + i]];
  if (s.parts[p].solve(std::span<const Vec3>(members, count))) s.store_solved(p);
}

bool MeshDeformer::solve_parts(std::span<const Vec3> markers) {
  if (!accepts(markers)) return false;
  for (int p = 0; p < part_count(); ++p) solve_part(p, markers);
  return true;
}

int MeshDeformer::part_count() const { return static_cast<int>(state_->parts.size()); }
int MeshDeformer::part_member_count(int p) const { return state_->parts[p].model().member_count(); }
int MeshDeformer::cluster_part(int c) const { return state_->clusters[c].part; }
bool MeshDeformer::cluster_in_upper_half(int c) const { return state_->clusters[c].upper_half; }

// Eq. 8 for one cluster's influences, times their beta: the quadratic field A_t q^0, the RBF
// term, then back to the world frame. Centres farther than 2 sigma from every deformed
// influence of the cluster add exactly zero to the RBF term, so only the others are gathered.
inline __attribute__((always_inline)) void MeshDeformer::State::deform_cluster(int c) {
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
// processors with AVX2 ran the baseline (measured 1.9x slower on this EPYC).
__attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
void MeshDeformer::deform_clusters(int begin, int end) {
  State& s = *state_;
  end = std::min(end, cluster_count());
  for (int c = std::max(begin, 0); c < end; ++c) s.deform_cluster(c);
}

int MeshDeformer::cluster_count() const { return static_cast<int>(state_->clusters.size()); }

void MeshDeformer::blend_vertices(int begin, int end, std::span<float> positions) const {
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
__attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
void MeshDeformer::vertex_normals(int begin, int end, std::span<const float> positions, std::span<float> normals) const {
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

bool MeshDeformer::deform(std::span<const Vec3> markers, std::span<float> positions, std::span<float> normals) {
  if (!solve_parts(markers)) return false;
  deform_clusters(0, cluster_count());
  blend_vertices(0, vertex_count(), positions);
  if (!normals.empty()) vertex_normals(0, vertex_count(), positions, normals);
  return true;
}

int MeshDeformer::vertex_count() const { return state_->vertex_count; }
int MeshDeformer::sequence_vertex(int slot) const {
  if (slot < 0 || slot >= state_->vertex_count) throw std::out_of_range("MeshDeformer::sequence_vertex: no such slot");
  return state_->window_sequence[static_cast<size_t>(slot / kNormalWindow)] * kNormalWindow + slot % kNormalWindow;
}
int MeshDeformer::upper_half_slot() const { return state_->half_slot; }
int MeshDeformer::normal_group_size() const { return kNormalWindow; }
DeformationMode MeshDeformer::mode() const { return state_->mode; }
const PartDeformer& MeshDeformer::part(int part) const { return state_->parts.at(static_cast<size_t>(part)); }

size_t MeshDeformer::memory_bytes() const {
  const State& s = *state_;
  auto bytes = [](const auto& v) { return v.capacity() * sizeof(v[0]); };
  size_t total = sizeof(State) + bytes(s.member_offsets) + bytes(s.member_markers) +
                 bytes(s.member_scratch) + bytes(s.influence_offsets) + bytes(s.influence_results) +
                 bytes(s.solved) + bytes(s.centres) + bytes(s.window_sequence) +
                 bytes(s.normal_window_blocks) + bytes(s.normal_block_rows) + bytes(s.normal_rows) + bytes(s.normal_block_reads_last) + bytes(s.clusters) +
                 bytes(s.cluster_lanes) + bytes(s.cluster_result);
  for (const PartDeformer& part : s.parts) {
    const int y = part.model().member_count();
    // Members' reference data (points, Q0, pseudo-inverse), the per-frame centres (twice),
    // positions, residuals and weights, the kernel (factored in place by LLT) and its LU.
    total += sizeof(PartDeformer) + static_cast<size_t>(y) * (3 + 3 + 9 + 9 + 3 + 3 + 3 + 3 + 3) * sizeof(double) +
             2 * static_cast<size_t>(y) * y * sizeof(double);
  }
  return total;
}

}  // namespace skinstream
