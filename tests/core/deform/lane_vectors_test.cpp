// The normals' point loads (four points as x y z _ in the segments of one register), the
// in-segment rotation, the segment stores and the lane minimum and maximum at every ISA level
// MeshDeformer is cloned for: GCC lowers the same shuffles differently for AVX-512, AVX2 and
// SSE2, and the deformer's other tests only run the clone of the machine they run on.
#include "core/deform/lane_vectors.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <iterator>
#include <random>
#include <string>
#include <vector>

namespace skinstream::simd {
namespace {

struct Loaded {
  Lanes quads;     // load_quads
  Lanes exactly;   // load_quads_exactly
  Lanes rotated;   // rotate_xyz of quads
  float low = 0.0f, high = 0.0f;  // lane_min, lane_max of quads
};

// The helpers inlined into a function compiled for one ISA level; `stored` gets segment q's
// x y z at 4 * q (store_xyz), its fourth float left as it was.
#define SKINSTREAM_LOAD_AT(name, ...)                                                  \
  __VA_ARGS__ void name(const float* p, const int* index, Loaded& out, float* stored) { \
    load_quads(p, index, out.quads);                                                   \
    load_quads_exactly(p, index, out.exactly);                                         \
    rotate_xyz(out.quads, out.rotated);                                                \
    lane_min(out.quads, out.low);                                                      \
    lane_max(out.quads, out.high);                                                     \
    store_xyz<0>(out.quads, stored);                                                   \
    store_xyz<1>(out.quads, stored + 4);                                               \
    store_xyz<2>(out.quads, stored + 8);                                               \
    store_xyz<3>(out.quads, stored + 12);                                              \
  }
SKINSTREAM_LOAD_AT(load_baseline)
#if defined(__x86_64__)
SKINSTREAM_LOAD_AT(load_v3, __attribute__((target("arch=x86-64-v3"))))
SKINSTREAM_LOAD_AT(load_v4, __attribute__((target("arch=x86-64-v4"))))
#endif

void check(void (*load)(const float*, const int*, Loaded&, float*), const std::string& level) {
  constexpr int kPoints = 500;
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> value(-1000.0f, 1000.0f);
  std::vector<float> p(3 * kPoints + 1);  // load_quads reads one float past a point
  for (float& f : p) f = value(rng);
  std::uniform_int_distribution<int> point(0, kPoints - 1);
  for (int trial = 0; trial < 200; ++trial) {
    int index[kQuadsPerLanes];
    for (int& i : index) i = 3 * point(rng);
    Loaded l;
    float stored[4 * kQuadsPerLanes];
    std::fill(std::begin(stored), std::end(stored), 5000.0f);  // outside the values' range
    load(p.data(), index, l, stored);
    float low = l.quads[0], high = l.quads[0];
    for (int lane = 1; lane < kLanes; ++lane) low = std::min(low, l.quads[lane]), high = std::max(high, l.quads[lane]);
    ASSERT_EQ(l.low, low) << level << ", trial " << trial;
    ASSERT_EQ(l.high, high) << level << ", trial " << trial;
    for (int q = 0; q < kQuadsPerLanes; ++q) {
      for (int a = 0; a < 3; ++a) ASSERT_EQ(stored[4 * q + a], p[index[q] + a]) << level << ", point " << q;
      ASSERT_EQ(stored[4 * q + 3], 5000.0f) << level << ", point " << q;
      const float* expected = &p[index[q]];
      for (int a = 0; a < 4; ++a) ASSERT_EQ(l.quads[4 * q + a], expected[a]) << level << ", trial " << trial << ", point " << q;
      for (int a = 0; a < 3; ++a) ASSERT_EQ(l.exactly[4 * q + a], expected[a]) << level << ", point " << q;
      ASSERT_EQ(l.exactly[4 * q + 3], 0.0f) << level << ", point " << q;
      ASSERT_EQ(l.rotated[4 * q + 0], expected[1]) << level << ", point " << q;  // y z x, the fourth kept
      ASSERT_EQ(l.rotated[4 * q + 1], expected[2]) << level;
      ASSERT_EQ(l.rotated[4 * q + 2], expected[0]) << level;
      ASSERT_EQ(l.rotated[4 * q + 3], expected[3]) << level;
    }
  }
}

TEST(LaneVectors, LoadsRotatesStoresAndReducesAtEveryIsaLevelTheDeformerIsClonedFor) {
  check(load_baseline, "baseline");
#if defined(__x86_64__)
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma"))
    check(load_v3, "x86-64-v3");
  else
    std::printf("x86-64-v3 not run: this CPU lacks AVX2/FMA\n");
  if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("avx512bw"))
    check(load_v4, "x86-64-v4");
  else
    std::printf("x86-64-v4 not run: this CPU lacks AVX-512\n");
#endif
}

}  // namespace
}  // namespace skinstream::simd
