#include "protocol/subscriber/frame_quantisation.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

namespace skinstream::subscriber {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// The encoding as docs/subscriber-protocol.md states it, one value at a time with the library's
// rounding: what the lane code must equal, bit for bit.
QuantisationBox reference_box(const std::vector<float>& p) {
  float lo[3], hi[3];
  for (int a = 0; a < 3; ++a) lo[a] = std::numeric_limits<float>::max(), hi[a] = std::numeric_limits<float>::lowest();
  for (size_t i = 0; i < p.size(); ++i) {
    if (!std::isfinite(p[i])) continue;
    lo[i % 3] = std::min(lo[i % 3], p[i]);
    hi[i % 3] = std::max(hi[i % 3], p[i]);
  }
  QuantisationBox box;
  for (int a = 0; a < 3; ++a) {
    if (lo[a] > hi[a]) lo[a] = hi[a] = 0.0f;
    box.lo[a] = lo[a];
    box.step[a] = (hi[a] - lo[a]) / 65535.0f;
  }
  return box;
}
uint16_t reference_position(float x, float lo, float step) {
  const double q = step > 0 && std::isfinite(x) ? std::round((x - lo) / step) : 0.0;
  return static_cast<uint16_t>(std::clamp(q, 0.0, 65535.0));
}
int16_t reference_normal(float n) {
  const float c = std::isfinite(n) ? std::clamp(n, -1.0f, 1.0f) : 0.0f;
  return static_cast<int16_t>(std::lround(c * 32767.0f));
}

template <typename T>
T code_at(const std::vector<unsigned char>& bytes, size_t i) {
  T v;
  std::memcpy(&v, bytes.data() + 2 * i, 2);
  return v;
}

void expect_positions_match_reference(const std::vector<float>& p) {
  const QuantisationBox box = quantisation_box(p), expected = reference_box(p);
  for (int a = 0; a < 3; ++a) {
    EXPECT_EQ(std::bit_cast<uint32_t>(box.lo[a]), std::bit_cast<uint32_t>(expected.lo[a])) << "axis " << a;
    EXPECT_EQ(std::bit_cast<uint32_t>(box.step[a]), std::bit_cast<uint32_t>(expected.step[a])) << "axis " << a;
  }
  std::vector<unsigned char> out(2 * p.size());
  quantise_positions(p, box, out.data());
  for (size_t i = 0; i < p.size(); ++i)
    ASSERT_EQ(code_at<uint16_t>(out, i), reference_position(p[i], expected.lo[i % 3], expected.step[i % 3]))
        << "value " << i << " = " << p[i];
}

TEST(FrameQuantisation, PositionsEqualTheLibrarysRoundingOnABodySizedCloud) {
  std::mt19937 random(3);
  std::uniform_real_distribution<float> body(-900.0f, 1900.0f);
  for (size_t vertices : {size_t{53'514}, size_t{13}, size_t{8}, size_t{1}}) {  // with and without a partial group
    std::vector<float> p(3 * vertices);
    for (float& x : p) x = body(random);
    SCOPED_TRACE(vertices);
    expect_positions_match_reference(p);
  }
}

// With 0 and 65535 on an axis its step is exactly 1, so x + 0.5 lands on a half: the ties must
// go up, as std::round sends them, not to even.
TEST(FrameQuantisation, PositionsRoundHalvesUp) {
  std::vector<float> p;
  for (int v = 0; v < 40; ++v) {
    const float x = v == 0 ? 0.0f : v == 1 ? 65535.0f : static_cast<float>(2 * v) + 0.5f;
    p.insert(p.end(), {x, x, x});
  }
  const QuantisationBox box = quantisation_box(p);
  ASSERT_EQ(box.step[0], 1.0f);
  std::vector<unsigned char> out(2 * p.size());
  quantise_positions(p, box, out.data());
  EXPECT_EQ(code_at<uint16_t>(out, 3 * 2), 5u);  // 4.5 -> 5
  EXPECT_EQ(code_at<uint16_t>(out, 3 * 3), 7u);  // 6.5 -> 7
  expect_positions_match_reference(p);
}

// A box other than the frame's own (values beyond it on both sides): codes clamp to 0 and
// 65535, as the reference's clamp does.
TEST(FrameQuantisation, PositionsOutsideTheBoxClampToItsEnds) {
  std::vector<float> p;
  for (int v = 0; v < 40; ++v) {
    const float x = -50.0f + 5.0f * static_cast<float>(v) + 0.3f;
    p.insert(p.end(), {x, -x, 0.5f * x});
  }
  QuantisationBox box;
  for (int a = 0; a < 3; ++a) box.lo[a] = -10.0f, box.step[a] = 40.0f / 65535.0f;
  std::vector<unsigned char> out(2 * p.size());
  quantise_positions(p, box, out.data());
  EXPECT_EQ(code_at<uint16_t>(out, 0), 0u);             // below lo
  EXPECT_EQ(code_at<uint16_t>(out, 3 * 39), 65535u);    // beyond lo + 65535 steps
  for (size_t i = 0; i < p.size(); ++i)
    ASSERT_EQ(code_at<uint16_t>(out, i), reference_position(p[i], box.lo[i % 3], box.step[i % 3])) << "value " << i;
}

TEST(FrameQuantisation, NonFiniteAndFlatAxesGiveZeroAndDoNotWidenTheBox) {
  std::vector<float> p;
  for (int v = 0; v < 30; ++v) {
    const float x = v % 5 == 0 ? kNaN : v % 7 == 0 ? kInf : v % 11 == 0 ? -kInf : static_cast<float>(v);
    p.insert(p.end(), {x, 42.0f, kNaN});  // y flat, z never finite
  }
  const QuantisationBox box = quantisation_box(p);
  EXPECT_EQ(box.lo[0], 1.0f);
  EXPECT_EQ(box.step[1], 0.0f);
  EXPECT_EQ(box.lo[2], 0.0f);
  EXPECT_EQ(box.step[2], 0.0f);
  std::vector<unsigned char> out(2 * p.size());
  quantise_positions(p, box, out.data());
  EXPECT_EQ(code_at<uint16_t>(out, 0), 0u);       // NaN
  EXPECT_EQ(code_at<uint16_t>(out, 3 * 29), 65535u);  // the greatest finite x
  EXPECT_EQ(code_at<uint16_t>(out, 1), 0u);       // flat axis
  expect_positions_match_reference(p);
}

TEST(FrameQuantisation, NormalsEqualTheLibrarysRoundingIncludingTiesClampsAndNonFinite) {
  std::mt19937 random(5);
  std::uniform_real_distribution<float> component(-1.2f, 1.2f);
  std::vector<float> n(3 * 53'514 + 5);
  for (float& c : n) c = component(random);
  // Components whose n * 32767 is exactly a half, both signs, and the special values.
  size_t at = 0;
  for (int k = 0; k < 32767 && at < 2000; k += 37) {
    const float c = (static_cast<float>(k) + 0.5f) / 32767.0f;
    if (c * 32767.0f != static_cast<float>(k) + 0.5f) continue;
    n[at++] = c;
    n[at++] = -c;
  }
  ASSERT_GT(at, 100u);
  for (float c : {kNaN, kInf, -kInf, -0.0f, 0.0f, 1.0f, -1.0f, 3.0f, -3.0f}) n[at++] = c;
  std::vector<unsigned char> out(2 * n.size());
  quantise_normals(n, out.data());
  for (size_t i = 0; i < n.size(); ++i) ASSERT_EQ(code_at<int16_t>(out, i), reference_normal(n[i])) << "component " << i << " = " << n[i];
}

}  // namespace
}  // namespace skinstream::subscriber
