// The normals' transposes (16 points as x y z triples <-> x, y, z in lanes) at every ISA level
// MeshDeformer is cloned for: GCC lowers the same shuffles differently for AVX-512, AVX2 and
// SSE2, and the deformer's other tests only run the clone of the machine they run on.
#include "core/deform/lane_vectors.h"

#include <gtest/gtest.h>

#include <random>
#include <string>
#include <vector>

namespace skinstream::simd {
namespace {

struct Transposed {
  Lanes x, y, z;        // load_points
  Lanes ex, ey, ez;     // load_points_exactly
  float stored[3 * kLanes];  // store_points of x, y, z
};

// The helpers inlined into a function compiled for one ISA level.
#define SKINSTREAM_TRANSPOSE_AT(name, ...)                                                        \
  __VA_ARGS__ void name(const float* p, const int* index, Transposed& out) {                      \
    load_points(p, index, out.x, out.y, out.z);                                                    \
    load_points_exactly(p, index, out.ex, out.ey, out.ez);                                         \
    store_points(out.stored, out.x, out.y, out.z);                                                 \
  }
SKINSTREAM_TRANSPOSE_AT(transpose_baseline)
#if defined(__x86_64__)
SKINSTREAM_TRANSPOSE_AT(transpose_v3, __attribute__((target("arch=x86-64-v3"))))
SKINSTREAM_TRANSPOSE_AT(transpose_v4, __attribute__((target("arch=x86-64-v4"))))
#endif

void check(void (*transpose)(const float*, const int*, Transposed&), const std::string& level) {
  constexpr int kPoints = 500;
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> value(-1000.0f, 1000.0f);
  std::vector<float> p(3 * kPoints + 1);  // load_points reads one float past a point
  for (float& f : p) f = value(rng);
  std::uniform_int_distribution<int> point(0, kPoints - 1);
  for (int trial = 0; trial < 200; ++trial) {
    int index[kLanes];
    for (int& i : index) i = 3 * point(rng);
    Transposed t;
    transpose(p.data(), index, t);
    for (int l = 0; l < kLanes; ++l) {
      const int lane = load_lane(l);  // the point loaded l-th lands in this lane
      const float* expected = &p[index[l]];
      ASSERT_EQ(t.x[lane], expected[0]) << level << ", trial " << trial << ", load " << l;
      ASSERT_EQ(t.y[lane], expected[1]) << level;
      ASSERT_EQ(t.z[lane], expected[2]) << level;
      ASSERT_EQ(t.ex[lane], expected[0]) << level;
      ASSERT_EQ(t.ey[lane], expected[1]) << level;
      ASSERT_EQ(t.ez[lane], expected[2]) << level;
    }
    for (int lane = 0; lane < kLanes; ++lane) {
      ASSERT_EQ(t.stored[3 * lane], t.x[lane]) << level << ", lane " << lane;
      ASSERT_EQ(t.stored[3 * lane + 1], t.y[lane]) << level;
      ASSERT_EQ(t.stored[3 * lane + 2], t.z[lane]) << level;
    }
  }
}

TEST(LaneVectors, LoadLaneIsItsOwnInverse) {
  for (int l = 0; l < kLanes; ++l) EXPECT_EQ(load_lane(load_lane(l)), l);
}

TEST(LaneVectors, TransposesAtEveryIsaLevelTheDeformerIsClonedFor) {
  check(transpose_baseline, "baseline");
#if defined(__x86_64__)
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma"))
    check(transpose_v3, "x86-64-v3");
  else
    std::printf("x86-64-v3 not run: this CPU lacks AVX2/FMA\n");
  if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("avx512bw"))
    check(transpose_v4, "x86-64-v4");
  else
    std::printf("x86-64-v4 not run: this CPU lacks AVX-512\n");
#endif
}

}  // namespace
}  // namespace skinstream::simd
