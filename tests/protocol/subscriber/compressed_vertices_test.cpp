#include "protocol/subscriber/compressed_vertices.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>

#include "protocol/subscriber/subscriber_stream.h"
#include "support/allocation_counter.h"

namespace skinstream::subscriber {
namespace {

// A body-sized cloud of points on a wavy sheet, moving and bending with time t (s).
struct MovingSheet {
  int side = 60;
  int vertex_count() const { return side * side; }
  std::vector<float> positions(double t) const {
    std::vector<float> out;
    for (int i = 0; i < side; ++i)
      for (int j = 0; j < side; ++j) {
        const double x = 10.0 * i, y = 30.0 * j;
        out.push_back(static_cast<float>(x + 400.0 * t));
        out.push_back(static_cast<float>(y + 20.0 * std::sin(x / 80.0 + 3.0 * t)));
        out.push_back(static_cast<float>(900.0 + 40.0 * std::sin(y / 200.0) * std::cos(2.0 * t)));
      }
    return out;
  }
  std::vector<float> normals(double t) const {
    std::vector<float> out;
    for (int k = 0; k < vertex_count(); ++k) {
      const double a = 0.7 * k + t, b = 0.3 * k;
      out.push_back(static_cast<float>(std::cos(a) * std::sin(b)));
      out.push_back(static_cast<float>(std::sin(a) * std::sin(b)));
      out.push_back(static_cast<float>(std::cos(b)));
    }
    return out;
  }
};

struct Blocks {
  std::vector<unsigned char> bytes;
  CompressedBlocks sizes;
  std::span<const unsigned char> positions() const { return std::span(bytes).first(sizes.positions_bytes); }
  std::span<const unsigned char> normals() const { return std::span(bytes).subspan(sizes.positions_bytes, sizes.normals_bytes); }
};

Blocks encode(CompressedVertexEncoder& encoder, uint32_t frame, const std::vector<float>& positions, const std::vector<float>& normals) {
  Blocks b;
  b.bytes.resize(encoder.max_bytes(!normals.empty()));
  b.sizes = encoder.encode(frame, positions, normals, b.bytes);
  b.bytes.resize(b.sizes.positions_bytes + b.sizes.normals_bytes);
  return b;
}

TEST(CompressedVertices, KeyAndDeltaFramesDecodeWithinHalfAGridStep) {
  const MovingSheet sheet;
  // Coded in the spatial order, read back into the mesh's.
  const std::vector<uint32_t> order = compressed_vertex_order(sheet.positions(0.0));
  CompressedVertexEncoder encoder(sheet.vertex_count(), order, 10);
  CompressedVertexDecoder decoder(sheet.vertex_count(), order);
  std::vector<float> positions(3 * sheet.vertex_count()), normals(positions.size());
  int keys = 0;
  size_t key_bytes = 0, delta_bytes = 0;
  for (uint32_t f = 0; f < 25; ++f) {
    const double t = f / 120.0;
    const std::vector<float> truth = sheet.positions(t), truth_normals = sheet.normals(t);
    const Blocks b = encode(encoder, 1000 + f, truth, truth_normals);
    keys += b.sizes.key;
    (b.sizes.key ? key_bytes : delta_bytes) += b.sizes.positions_bytes;
    EXPECT_EQ(b.sizes.key, f % 10 == 0) << f;  // every 10th, nothing leaves the grid here
    ASSERT_EQ(decoder.decode(b.positions(), b.normals(), b.sizes.key, positions, normals), CompressedVertexDecoder::Result::Decoded);
    // The grid's step on its widest axis (y: about 1,810 mm of sheet plus 2 x 250 mm), over 65535.
    const double step = (1850.0 + 500.0) / 65535.0;
    for (size_t i = 0; i < truth.size(); ++i) ASSERT_NEAR(positions[i], truth[i], 0.5 * step + 1e-3) << "frame " << f << " value " << i;
    for (size_t v = 0; v < truth.size() / 3; ++v) {
      double dot = 0.0;
      for (int a = 0; a < 3; ++a) dot += double(normals[3 * v + a]) * truth_normals[3 * v + a];
      ASSERT_GT(dot, std::cos(1.5 * M_PI / 180.0)) << "normal " << v << " of frame " << f;
    }
  }
  EXPECT_EQ(keys, 3);
  // Delta frames of a smooth motion code smaller than key frames.
  EXPECT_LT(delta_bytes / 22.0, key_bytes / 3.0);
}

TEST(CompressedVertices, ALateDecoderWaitsForTheNextKey) {
  const MovingSheet sheet;
  CompressedVertexEncoder encoder(sheet.vertex_count(), {}, 5);
  CompressedVertexDecoder decoder(sheet.vertex_count());
  std::vector<float> positions(3 * sheet.vertex_count());
  for (uint32_t f = 0; f < 12; ++f) {
    const Blocks b = encode(encoder, f, sheet.positions(f / 120.0), {});
    if (f < 2) continue;  // the decoder joins at frame 2: it never sees key 0
    const auto result = decoder.decode(b.positions(), {}, b.sizes.key, positions, {});
    EXPECT_EQ(result, f < 5 ? CompressedVertexDecoder::Result::NeedsKey : CompressedVertexDecoder::Result::Decoded) << f;
  }
}

TEST(CompressedVertices, LeavingTheGridOrARequestMakesAKeyAtOnce) {
  const MovingSheet sheet;
  CompressedVertexEncoder encoder(sheet.vertex_count(), {}, 1000, 10.0f);
  std::vector<float> frame = sheet.positions(0.0);
  EXPECT_TRUE(encode(encoder, 0, frame, {}).sizes.key);
  for (size_t i = 0; i < frame.size(); i += 3) frame[i] += 5.0f;  // within the 10 mm margin
  EXPECT_FALSE(encode(encoder, 1, frame, {}).sizes.key);
  frame[0] -= 30.0f;  // one coordinate beyond it (vertex 0 had the least x)
  EXPECT_TRUE(encode(encoder, 2, frame, {}).sizes.key);
  EXPECT_FALSE(encode(encoder, 3, frame, {}).sizes.key);
  encoder.request_key();
  EXPECT_TRUE(encode(encoder, 4, frame, {}).sizes.key);
  EXPECT_FALSE(encode(encoder, 5, frame, {}).sizes.key);
}

TEST(CompressedVertices, EncodingAndDecodingAllocateNothing) {
  const MovingSheet sheet;
  CompressedVertexEncoder encoder(sheet.vertex_count(), {}, 4);
  CompressedVertexDecoder decoder(sheet.vertex_count());
  const std::vector<float> a = sheet.positions(0.0), n = sheet.normals(0.0);
  std::vector<unsigned char> out(encoder.max_bytes(true));
  std::vector<float> positions(a.size()), normals(a.size());
  test::CountAllocations count;
  for (uint32_t f = 0; f < 6; ++f) {
    const CompressedBlocks sizes = encoder.encode(f, a, n, out);
    decoder.decode(std::span(out).first(sizes.positions_bytes), std::span(out).subspan(sizes.positions_bytes, sizes.normals_bytes),
                   sizes.key, positions, normals);
  }
  EXPECT_EQ(count.count(), 0u);
}

TEST(CompressedVertices, TheOrderIsAPermutationOrRefused) {
  const MovingSheet sheet;
  const std::vector<uint32_t> order = compressed_vertex_order(sheet.positions(0.0));
  std::vector<uint32_t> sorted = order;
  std::sort(sorted.begin(), sorted.end());
  for (uint32_t v = 0; v < sorted.size(); ++v) ASSERT_EQ(sorted[v], v);
  std::vector<uint32_t> twice = order;
  twice[1] = twice[0];
  EXPECT_THROW(CompressedVertexDecoder(sheet.vertex_count(), twice), std::invalid_argument);
  EXPECT_THROW(CompressedVertexEncoder(sheet.vertex_count(), std::vector<uint32_t>(order.begin(), order.end() - 1)), std::invalid_argument);
}

TEST(CompressedVertices, BadBlocksAreRejected) {
  const MovingSheet sheet;
  CompressedVertexEncoder encoder(sheet.vertex_count());
  CompressedVertexDecoder decoder(sheet.vertex_count());
  const Blocks b = encode(encoder, 7, sheet.positions(0.0), sheet.normals(0.0));
  std::vector<float> positions(3 * sheet.vertex_count()), normals(positions.size());
  std::vector<unsigned char> bad(b.positions().begin(), b.positions().end());
  bad.resize(bad.size() - 4);  // shorter than its count says
  EXPECT_THROW(decoder.decode(bad, {}, true, positions, {}), DecodeError);
  bad.assign(b.positions().begin(), b.positions().end());
  const float zero = 0.0f;
  std::memcpy(bad.data() + 16, &zero, 4);  // a grid step of 0
  EXPECT_THROW(decoder.decode(bad, {}, true, positions, {}), DecodeError);
  // A grid whose far corner (origin + 65535 steps) is beyond float range: the positions would
  // decode to infinity (found by fuzzing: a step of 1e35 passed as a finite positive number).
  for (const auto& [origin, step] : {std::pair{0.0f, 1e35f}, std::pair{3e38f, 1e34f}, std::pair{-3e38f, 1e34f}}) {
    SCOPED_TRACE(step);
    bad.assign(b.positions().begin(), b.positions().end());
    std::memcpy(bad.data() + 4, &origin, 4);
    std::memcpy(bad.data() + 16, &step, 4);
    EXPECT_THROW(decoder.decode(bad, {}, true, positions, {}), DecodeError);
  }
  bad.assign(b.positions().begin(), b.positions().end());
  bad[32] ^= 0xFF;  // the codec's header byte
  EXPECT_THROW(decoder.decode(bad, {}, true, positions, {}), DecodeError);
  std::vector<unsigned char> bad_normals(b.normals().begin(), b.normals().end());
  bad_normals.resize(bad_normals.size() - 4);
  EXPECT_THROW(decoder.decode(b.positions(), bad_normals, true, positions, normals), DecodeError);
}

// 8-bit octahedral normals, made unit again on decoding: the worst of 100,000 random directions
// is 1.17 degrees off, of the demo body's normals over 40 frames 1.25.
TEST(CompressedVertices, NormalsComeBackWithin1Point5Degrees) {
  std::mt19937 rng(5);
  std::normal_distribution<float> g;
  const int n = 100000;
  std::vector<float> normals(3 * n), positions(3 * n, 0.0f), out_p(3 * n), out_n(3 * n);
  for (int i = 0; i < n; ++i) {
    float x = g(rng), y = g(rng), z = g(rng), l = std::sqrt(x * x + y * y + z * z);
    normals[3 * i] = x / l, normals[3 * i + 1] = y / l, normals[3 * i + 2] = z / l;
  }
  CompressedVertexEncoder encoder(n);
  CompressedVertexDecoder decoder(n);
  const Blocks b = encode(encoder, 0, positions, normals);
  decoder.decode(b.positions(), b.normals(), true, out_p, out_n);
  double worst = 0;
  for (int i = 0; i < n; ++i) {
    double dot = 0;
    for (int a = 0; a < 3; ++a) dot += double(out_n[3 * i + a]) * normals[3 * i + a];
    worst = std::max(worst, std::acos(std::min(dot, 1.0)) * 180 / M_PI);
  }
  EXPECT_LT(worst, 1.5);
}

}  // namespace
}  // namespace skinstream::subscriber
