#include "protocol/subscriber/frame_quantisation.h"

#include <algorithm>
#include <bit>
#include <cstring>
#include <limits>

namespace skinstream::subscriber {
namespace {

static_assert(std::endian::native == std::endian::little, "the protocol is little-endian; a big-endian host must swap");

// Eight floats: with the x86-64-v3 build one AVX register, two SSE ones in the baseline build.
// Vertices go 8 at a time, 24 floats, as three of these, where the axes repeat with period 3:
// lane l of block k holds axis (8k + l) % 3.
constexpr int kLanes = 8;
constexpr int kGroup = 3 * kLanes;  // floats in 8 vertices
typedef float F8 __attribute__((vector_size(kLanes * sizeof(float))));
typedef int32_t I8 __attribute__((vector_size(kLanes * sizeof(int32_t))));
typedef uint16_t U8 __attribute__((vector_size(kLanes * sizeof(uint16_t))));
typedef int16_t S8 __attribute__((vector_size(kLanes * sizeof(int16_t))));

inline __attribute__((always_inline)) F8 load8(const float* from) {
  F8 v;
  std::memcpy(&v, from, sizeof v);
  return v;
}

// Per axis, the value each lane of block k needs.
inline __attribute__((always_inline)) F8 axis_pattern(const float per_axis[3], int block) {
  F8 v;
  for (int l = 0; l < kLanes; ++l) v[l] = per_axis[(kLanes * block + l) % 3];
  return v;
}

// round(t), halves away from zero, for 0 <= t < 2^31: truncation is the floor there, and
// t - floor(t) is exact, so this is std::round's value in operations that stay in lanes.
inline __attribute__((always_inline)) I8 round_nonnegative(F8 t) {
  const I8 whole = __builtin_convertvector(t, I8);
  const F8 fraction = t - __builtin_convertvector(whole, F8);
  return whole - (fraction >= 0.5f);  // a true comparison is -1
}

// x - x is 0 exactly when x is finite (inf - inf and NaN give NaN).
inline __attribute__((always_inline)) I8 finite(F8 x) { return (x - x) == 0.0f; }

inline __attribute__((always_inline)) U8 quantise_positions8(F8 x, F8 lo, F8 step) {
  const F8 zero = {};
  // Not below 0 with the frame's own box (lo is the least); clamped for any other box.
  F8 t = (finite(x) & (step > 0.0f)) ? (x - lo) / step : zero;
  t = t > zero ? t : zero;
  I8 q = round_nonnegative(t);
  q = q > 65535 ? 65535 : q;
  return __builtin_convertvector(q, U8);
}

inline __attribute__((always_inline)) S8 quantise_normals8(F8 n) {
  const F8 zero = {}, one = zero + 1.0f;
  F8 c = n < -one ? -one : (n > one ? one : n);  // std::clamp's order of tests
  c = finite(n) ? c : zero;
  const F8 t = c * 32767.0f;
  const I8 magnitude = round_nonnegative(t < zero ? -t : t);
  return __builtin_convertvector(t < zero ? -magnitude : magnitude, S8);
}

// Runs `block(values, codes)` over the floats kFloats at a time, codes being where the block's
// 2 bytes a float go in `out` (null when out is: a block that writes nothing). The last, partial
// block is padded with `pad` and its codes cut to size, so every value goes through the same
// lane code.
template <size_t kFloats, typename Block>
inline __attribute__((always_inline)) void for_each_block(std::span<const float> in, float pad, unsigned char* out,
                                                          Block block) {
  const size_t whole = in.size() / kFloats, rest = in.size() % kFloats;
  for (size_t b = 0; b < whole; ++b) block(in.data() + b * kFloats, out ? out + 2 * b * kFloats : nullptr);
  if (rest == 0) return;
  float tail[kFloats];
  std::fill(tail, tail + kFloats, pad);
  std::memcpy(tail, in.data() + whole * kFloats, rest * sizeof(float));
  unsigned char codes[2 * kFloats];
  block(tail, codes);
  if (out) std::memcpy(out + 2 * whole * kFloats, codes, 2 * rest);
}

}  // namespace

QuantisationBox quantisation_box(std::span<const float> positions) {
  float lo[3], hi[3];
  for (int a = 0; a < 3; ++a) lo[a] = std::numeric_limits<float>::max(), hi[a] = std::numeric_limits<float>::lowest();
  F8 lo8[3], hi8[3];
  for (int k = 0; k < 3; ++k) lo8[k] = axis_pattern(lo, k), hi8[k] = axis_pattern(hi, k);
  // Padding with NaN: not finite, so it moves no bound.
  for_each_block<kGroup>(positions.first(positions.size() - positions.size() % 3), std::numeric_limits<float>::quiet_NaN(),
                         nullptr, [&](const float* group, unsigned char*) {
                           for (int k = 0; k < 3; ++k) {
                             const F8 x = load8(group + k * kLanes);
                             const I8 ok = finite(x);
                             lo8[k] = (ok & (x < lo8[k])) ? x : lo8[k];
                             hi8[k] = (ok & (x > hi8[k])) ? x : hi8[k];
                           }
                         });
  for (int k = 0; k < 3; ++k)
    for (int l = 0; l < kLanes; ++l) {
      const int a = (kLanes * k + l) % 3;
      lo[a] = std::min(lo[a], lo8[k][l]);
      hi[a] = std::max(hi[a], hi8[k][l]);
    }
  QuantisationBox box;
  for (int a = 0; a < 3; ++a) {
    if (lo[a] > hi[a]) lo[a] = hi[a] = 0.0f;  // no finite value on this axis
    box.lo[a] = lo[a];
    box.step[a] = (hi[a] - lo[a]) / 65535.0f;
  }
  return box;
}

void quantise_positions(std::span<const float> positions, const QuantisationBox& box, unsigned char* out) {
  F8 lo8[3], step8[3];
  for (int k = 0; k < 3; ++k) lo8[k] = axis_pattern(box.lo, k), step8[k] = axis_pattern(box.step, k);
  for_each_block<kGroup>(positions, 0.0f, out, [&](const float* group, unsigned char* codes) {
    for (int k = 0; k < 3; ++k) {
      const U8 block = quantise_positions8(load8(group + k * kLanes), lo8[k], step8[k]);
      std::memcpy(codes + 2 * k * kLanes, &block, sizeof block);
    }
  });
}

void quantise_normals(std::span<const float> normals, unsigned char* out) {
  for_each_block<kLanes>(normals, 0.0f, out, [](const float* block, unsigned char* codes) {
    const S8 values = quantise_normals8(load8(block));
    std::memcpy(codes, &values, sizeof values);
  });
}

}  // namespace skinstream::subscriber
