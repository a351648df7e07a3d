// Cost of encoding one Frame message of the subscriber protocol on the daemon's 120 Hz thread,
// for the 53,514-vertex mesh and 350 markers, in the encodings a subscriber may ask for; and
// a plain copy of the same bytes as the floor. Each message goes into a buffer of its own
// size, several in turn, as the daemon's pool of encoded frames does (so the writes do not
// stay in one warm buffer).
//   build/bin/encode_benchmark --benchmark_format=json
#include <benchmark/benchmark.h>

#include <cstring>
#include <random>
#include <vector>

#include "protocol/subscriber/subscriber_stream.h"

namespace skinstream {
namespace {

constexpr uint32_t kVertices = 53'514;
constexpr uint32_t kMarkers = 350;
constexpr int kPooledBuffers = 8;  // the daemon's pool at start

struct FrameData {
  std::vector<float> positions, normals, markers;
  std::vector<uint8_t> status;
  FrameData() : positions(3 * kVertices), normals(3 * kVertices), markers(3 * kMarkers), status(kMarkers, 0) {
    std::mt19937 random(1);
    std::uniform_real_distribution<float> body(-900.0f, 900.0f), unit(-1.0f, 1.0f);
    for (float& p : positions) p = body(random);
    for (float& n : normals) n = unit(random);
    for (float& m : markers) m = body(random);
  }
};

void encode(benchmark::State& state, uint32_t flags) {
  const FrameData data;
  subscriber::FrameInfo info;
  info.flags = flags;
  info.vertex_count = kVertices;
  info.marker_count = kMarkers;
  const size_t bytes = subscriber::frame_message_bytes(flags, kVertices, kMarkers);
  std::vector<std::vector<unsigned char>> pool(kPooledBuffers, std::vector<unsigned char>(bytes));
  int next = 0;
  for (auto _ : state) {
    ++info.frame_number;
    subscriber::encode_frame(info, data.positions, data.normals, data.markers, data.status, pool[next]);
    benchmark::DoNotOptimize(pool[next].data());
    next = (next + 1) % kPooledBuffers;
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations() * bytes));
}

void BM_EncodePositions(benchmark::State& state) { encode(state, 0); }
void BM_EncodePositionsNormals(benchmark::State& state) { encode(state, subscriber::kFrameNormals); }
void BM_EncodeQuantisedPositionsNormals(benchmark::State& state) {
  encode(state, subscriber::kFrameNormals | subscriber::kFrameQuantised);
}
void BM_EncodeMarkersOnly(benchmark::State& state) {
  encode(state, subscriber::kFrameMarkers | subscriber::kFrameNoPositions);
}

// The floor: the float32 positions' bytes copied into the same pool.
void BM_CopyPositionsBytes(benchmark::State& state) {
  const FrameData data;
  const size_t bytes = data.positions.size() * sizeof(float);
  std::vector<std::vector<unsigned char>> pool(kPooledBuffers, std::vector<unsigned char>(bytes));
  int next = 0;
  for (auto _ : state) {
    std::memcpy(pool[next].data(), data.positions.data(), bytes);
    benchmark::DoNotOptimize(pool[next].data());
    next = (next + 1) % kPooledBuffers;
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations() * bytes));
}

BENCHMARK(BM_EncodePositions);
BENCHMARK(BM_EncodePositionsNormals);
BENCHMARK(BM_EncodeQuantisedPositionsNormals);
BENCHMARK(BM_EncodeMarkersOnly);
BENCHMARK(BM_CopyPositionsBytes);

}  // namespace
}  // namespace skinstream

BENCHMARK_MAIN();
