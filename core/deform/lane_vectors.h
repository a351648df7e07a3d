#pragma once
// The vector lanes MeshDeformer computes in (GCC vector extensions, so one source serves the
// AVX-512, AVX2 and baseline clones of its loops), and the transposes between 16 points stored
// as x y z triples and their x, y and z in lanes. Internal to core/deform; in a header so the
// tests can run the transposes at every ISA level.

namespace skinstream::simd {

// Lanes of influences evaluated together: 16 floats are one AVX-512 register, two AVX2 ones.
// Everything the vector clones of deform_clusters call is always_inline or a builtin: GCC does
// not inline default-target functions such as std::max or std::sqrt into them, and a call in a
// loop stops it vectorising (the loop ran scalar until this was found in the disassembly).
constexpr int kLanes = 16;
typedef float Lanes __attribute__((vector_size(kLanes * sizeof(float))));

// Where the normals read positions, 16 points at a time: each point's x y z and the float after
// it in one 4-float load, four loads joined into one 16-float register, and a 4 x 4 transpose
// inside every 128-bit segment gives x, y and z in lanes (instead of 48 single-float loads and
// inserts). The transpose leaves the point loaded l-th in lane load_lane(l), so the rows of
// indices are stored in that order (the map is its own inverse).
static_assert(kLanes == 16, "the transpose joins four 4-float loads four times");
constexpr int load_lane(int l) { return 4 * (l % 4) + l / 4; }
typedef float Quad __attribute__((vector_size(4 * sizeof(float))));
typedef float Octet __attribute__((vector_size(8 * sizeof(float))));

inline __attribute__((always_inline)) Quad load_quad(const float* from) {
  Quad q;
  __builtin_memcpy(&q, from, sizeof(Quad));
  return q;
}

// x, y, z of the points p + index[l] (float indices, in load order; each point must be followed
// by at least one readable float), in lanes in natural order.
inline __attribute__((always_inline)) void load_points(const float* __restrict p, const int* __restrict index, Lanes& x,
                                                       Lanes& y, Lanes& z) {
  Lanes joined[4];
  for (int j = 0; j < 4; ++j) {
    const Octet low = __builtin_shufflevector(load_quad(p + index[4 * j]), load_quad(p + index[4 * j + 1]), 0, 1, 2, 3, 4,
                                              5, 6, 7);
    const Octet high = __builtin_shufflevector(load_quad(p + index[4 * j + 2]), load_quad(p + index[4 * j + 3]), 0, 1, 2,
                                               3, 4, 5, 6, 7);
    joined[j] = __builtin_shufflevector(low, high, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
  }
  // Segment s of joined[j] is x y z _ of the point loaded (4j + s)-th.
  const Lanes xy01 = __builtin_shufflevector(joined[0], joined[1], 0, 16, 1, 17, 4, 20, 5, 21, 8, 24, 9, 25, 12, 28, 13, 29);
  const Lanes z_01 = __builtin_shufflevector(joined[0], joined[1], 2, 18, 3, 19, 6, 22, 7, 23, 10, 26, 11, 27, 14, 30, 15, 31);
  const Lanes xy23 = __builtin_shufflevector(joined[2], joined[3], 0, 16, 1, 17, 4, 20, 5, 21, 8, 24, 9, 25, 12, 28, 13, 29);
  const Lanes z_23 = __builtin_shufflevector(joined[2], joined[3], 2, 18, 3, 19, 6, 22, 7, 23, 10, 26, 11, 27, 14, 30, 15, 31);
  x = __builtin_shufflevector(xy01, xy23, 0, 1, 16, 17, 4, 5, 20, 21, 8, 9, 24, 25, 12, 13, 28, 29);
  y = __builtin_shufflevector(xy01, xy23, 2, 3, 18, 19, 6, 7, 22, 23, 10, 11, 26, 27, 14, 15, 30, 31);
  z = __builtin_shufflevector(z_01, z_23, 0, 1, 16, 17, 4, 5, 20, 21, 8, 9, 24, 25, 12, 13, 28, 29);
}

// Stores 16 points' x, y, z (lanes in natural order) as 48 consecutive floats x0 y0 z0 x1 ...,
// three 16-float stores instead of 48 single-float ones: per store, x and y are shuffled into
// place, then z.
inline __attribute__((always_inline)) void store_points(float* __restrict out, const Lanes& x, const Lanes& y,
                                                        const Lanes& z) {
  const Lanes chunk0 = __builtin_shufflevector(
      __builtin_shufflevector(x, y, 0, 16, 0, 1, 17, 0, 2, 18, 0, 3, 19, 0, 4, 20, 0, 5), z, 0, 1, 16, 3, 4, 17, 6, 7,
      18, 9, 10, 19, 12, 13, 20, 15);
  const Lanes chunk1 = __builtin_shufflevector(
      __builtin_shufflevector(x, y, 21, 0, 6, 22, 0, 7, 23, 0, 8, 24, 0, 9, 25, 0, 10, 26), z, 0, 21, 2, 3, 22, 5, 6, 23,
      8, 9, 24, 11, 12, 25, 14, 15);
  const Lanes chunk2 = __builtin_shufflevector(
      __builtin_shufflevector(x, y, 0, 11, 27, 0, 12, 28, 0, 13, 29, 0, 14, 30, 0, 15, 31, 0), z, 26, 1, 2, 27, 4, 5, 28,
      7, 8, 29, 10, 11, 30, 13, 14, 31);
  __builtin_memcpy(out, &chunk0, sizeof(Lanes));
  __builtin_memcpy(out + kLanes, &chunk1, sizeof(Lanes));
  __builtin_memcpy(out + 2 * kLanes, &chunk2, sizeof(Lanes));
}

// The same with single-float loads, for blocks that read the mesh's last vertex (no float
// after it in the caller's buffer).
inline __attribute__((always_inline)) void load_points_exactly(const float* __restrict p, const int* __restrict index,
                                                               Lanes& x, Lanes& y, Lanes& z) {
  for (int l = 0; l < kLanes; ++l) {
    const int lane = load_lane(l);
    x[lane] = p[index[l]], y[lane] = p[index[l] + 1], z[lane] = p[index[l] + 2];
  }
}

}  // namespace skinstream::simd
