#pragma once
// The vector lanes MeshEvaluator computes in (GCC vector extensions, so one source serves the
// AVX-512, AVX2 and baseline clones of its loops), and how the normals load points into them:
// four points as x y z _ in the four 128-bit segments of one register. Internal to
// core/deform; in a header so the tests can run the helpers at every ISA level.
// The helpers write through references instead of returning a vector: a vector return changes
// the ABI between ISA levels, and GCC warns about it in every file that includes this one.

namespace skinstream::simd {

// Lanes of influences evaluated together: 16 floats are one AVX-512 register, two AVX2 ones.
// Everything the vector clones of deform_clusters call is always_inline or a builtin: GCC does
// not inline default-target functions such as std::max or std::sqrt into them, and a call in a
// loop stops it vectorising (the loop ran scalar until this was found in the disassembly).
constexpr int kLanes = 16;
typedef float Lanes __attribute__((vector_size(kLanes * sizeof(float))));
typedef float Quad __attribute__((vector_size(4 * sizeof(float))));
typedef float Octet __attribute__((vector_size(8 * sizeof(float))));
// Points per register in the x y z _ layout: one per 128-bit segment.
constexpr int kQuadsPerLanes = kLanes / 4;
static_assert(kQuadsPerLanes == 4, "load_quads joins four 4-float loads");

inline __attribute__((always_inline)) Quad load_quad(const float* from) {
  Quad q;
  __builtin_memcpy(&q, from, sizeof(Quad));
  return q;
}

// The points p + index[0..3] (float indices; each point must be followed by at least one
// readable float, which lands in the segment's fourth lane) as x y z _ in segments 0..3: four
// 4-float loads joined by three shuffles.
inline __attribute__((always_inline)) void load_quads(const float* __restrict p, const int* __restrict index,
                                                      Lanes& out) {
  const Octet low = __builtin_shufflevector(load_quad(p + index[0]), load_quad(p + index[1]), 0, 1, 2, 3, 4, 5, 6, 7);
  const Octet high = __builtin_shufflevector(load_quad(p + index[2]), load_quad(p + index[3]), 0, 1, 2, 3, 4, 5, 6, 7);
  out = __builtin_shufflevector(low, high, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
}

// The same with 3-float loads and 0 in the fourth lanes, for points with nothing after them
// (the last point of the caller's buffer).
inline __attribute__((always_inline)) void load_quads_exactly(const float* __restrict p, const int* __restrict index,
                                                              Lanes& out) {
  out = Lanes{};
  for (int q = 0; q < kQuadsPerLanes; ++q)
    for (int a = 0; a < 3; ++a) out[4 * q + a] = p[index[q] + a];
}

// Segment kSegment's x y z to `to` (12 bytes, nothing after them touched), straight from the
// register: copying the register to memory and the floats from there stalled on forwarding the
// store (a quarter of the normals stage in perf).
template <int kSegment>
inline __attribute__((always_inline)) void store_xyz(const Lanes& v, float* to) {
  typedef float Pair __attribute__((vector_size(2 * sizeof(float))));
  const Quad q = __builtin_shufflevector(v, v, 4 * kSegment, 4 * kSegment + 1, 4 * kSegment + 2, 4 * kSegment + 3);
  const Pair xy = __builtin_shufflevector(q, q, 0, 1);
  __builtin_memcpy(to, &xy, sizeof(Pair));
  to[2] = q[2];
}

// The smallest (kLargest false) or the largest of the lanes: four halving steps of shuffles and
// selects, where reading the sixteen lanes one by one went through memory (a tenth of the
// cluster stage).
template <bool kLargest>
inline __attribute__((always_inline)) void lane_extreme(const Lanes& v, float& out) {
  Lanes m = v;
  auto keep = [&m](const Lanes& s) __attribute__((always_inline)) { m = (kLargest ? s > m : s < m) ? s : m; };
  keep(__builtin_shufflevector(m, m, 8, 9, 10, 11, 12, 13, 14, 15, 0, 1, 2, 3, 4, 5, 6, 7));
  keep(__builtin_shufflevector(m, m, 4, 5, 6, 7, 0, 1, 2, 3, 12, 13, 14, 15, 8, 9, 10, 11));
  keep(__builtin_shufflevector(m, m, 2, 3, 0, 1, 6, 7, 4, 5, 10, 11, 8, 9, 14, 15, 12, 13));
  keep(__builtin_shufflevector(m, m, 1, 0, 3, 2, 5, 4, 7, 6, 9, 8, 11, 10, 13, 12, 15, 14));
  out = m[0];
}
inline __attribute__((always_inline)) void lane_min(const Lanes& v, float& out) { lane_extreme<false>(v, out); }
inline __attribute__((always_inline)) void lane_max(const Lanes& v, float& out) { lane_extreme<true>(v, out); }

// x y z w -> y z x w in every segment (one in-segment permute). Applied to a * rotated(b) -
// rotated(a) * b it gives the cross product a x b.
inline __attribute__((always_inline)) void rotate_xyz(const Lanes& v, Lanes& out) {
  out = __builtin_shufflevector(v, v, 1, 2, 0, 3, 5, 6, 4, 7, 9, 10, 8, 11, 13, 14, 12, 15);
}

}  // namespace skinstream::simd
