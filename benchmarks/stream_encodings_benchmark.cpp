// What each encoding of the subscriber protocol (version 2) costs per frame, on one core, for the
// ~53,500-vertex body of benchmarks/punch_scenario.h deformed through its punching take:
//   - parameters: the daemon's part fits alone (all it computes when no subscriber wants
//     vertices), encoding and decoding the ~8 kB block, and a renderer's evaluation of the
//     parameters with the client library's code (MeshEvaluator), with and without normals;
//   - compressed: the vertex codec's encoding (key and delta frames in turn, as the stream
//     sends them) and decoding, with the bytes per frame.
//   build/bin/stream_encodings_benchmark --benchmark_format=json
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>

#include "benchmarks/punch_scenario.h"
#include "core/deform/mesh_deformer.h"
#include "core/deform/mesh_evaluator.h"
#include "protocol/subscriber/compressed_vertices.h"
#include "protocol/subscriber/frame_parameters.h"

namespace skinstream {
namespace {

// Every frame of the take deformed once: its parameters, positions and normals.
struct DeformedTake {
  EvaluationModel model;
  std::vector<FrameParameters> parameters;
  std::vector<std::vector<float>> positions, normals;
};

const DeformedTake& deformed_take() {
  static const DeformedTake take = [] {
    const Scenario& s = scenario();
    MeshDeformer deformer(s.model, s.subject);
    DeformedTake out;
    out.model = deformer.evaluation_model();
    for (const std::vector<Vec3>& markers : s.frames) {
      std::vector<float> p(3 * static_cast<size_t>(deformer.vertex_count())), n(p.size());
      deformer.deform(markers, p, n);
      out.parameters.push_back(deformer.parameters());
      out.positions.push_back(std::move(p));
      out.normals.push_back(std::move(n));
    }
    return out;
  }();
  return take;
}

void percentiles(benchmark::State& state, std::vector<double>& micros) {
  std::sort(micros.begin(), micros.end());
  auto at = [&](double q) { return micros[std::min(micros.size() - 1, static_cast<size_t>(q * micros.size()))]; };
  state.counters["p50_us"] = at(0.50);
  state.counters["p99_us"] = at(0.99);
}

template <typename Work>
void timed(benchmark::State& state, size_t frames, Work&& work) {
  std::vector<double> micros;
  micros.reserve(1 << 16);
  size_t frame = 0;
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    work(frame);
    micros.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count());
    frame = (frame + 1) % frames;
  }
  percentiles(state, micros);
}

// The daemon with only parameter subscribers: every part fitted, no vertex evaluated.
void BM_FitPartsOnly(benchmark::State& state) {
  const Scenario& s = scenario();
  MeshDeformer deformer(s.model, s.subject);
  timed(state, s.frames.size(), [&](size_t f) { benchmark::DoNotOptimize(deformer.solve_parts(s.frames[f])); });
}

// A renderer turning a frame's parameters into vertices (argument 1: and normals), one core.
void BM_EvaluateParameters(benchmark::State& state) {
  const DeformedTake& take = deformed_take();
  MeshEvaluator evaluator(take.model);
  std::vector<float> positions(take.model.reference_vertices.size()), normals(positions.size());
  const bool with_normals = state.range(0) != 0;
  timed(state, take.parameters.size(), [&](size_t f) {
    evaluator.evaluate(take.parameters[f], positions, with_normals ? std::span<float>(normals) : std::span<float>());
    benchmark::DoNotOptimize(positions.data());
  });
  state.counters["vertices"] = evaluator.vertex_count();
  state.counters["evaluator_bytes"] = static_cast<double>(evaluator.memory_bytes());
}

void BM_EncodeDecodeParameterBlock(benchmark::State& state) {
  const DeformedTake& take = deformed_take();
  std::vector<unsigned char> block(subscriber::parameter_block_bytes(take.model.part_count(), take.model.member_count()));
  FrameParameters decoded;
  decoded.resize(take.model.part_count(), take.model.member_count());
  timed(state, take.parameters.size(), [&](size_t f) {
    subscriber::encode_parameter_block(take.parameters[f], block);
    subscriber::decode_parameter_block(block, decoded);
  });
  state.counters["block_bytes"] = static_cast<double>(block.size());
}

// The compressed stream's encoding over the take (argument 1: with normals); bytes per frame
// averaged over key and delta frames as sent (a key every 10 frames).
void BM_EncodeCompressed(benchmark::State& state) {
  const DeformedTake& take = deformed_take();
  const bool with_normals = state.range(0) != 0;
  const int v = take.model.vertex_count();
  subscriber::CompressedVertexEncoder encoder(v, subscriber::compressed_vertex_order(take.model.reference_vertices));
  std::vector<unsigned char> out(encoder.max_bytes(with_normals));
  double bytes = 0.0, frames = 0.0;
  uint32_t number = 0;
  timed(state, take.positions.size(), [&](size_t f) {
    const subscriber::CompressedBlocks b = encoder.encode(number++, take.positions[f], with_normals ? std::span<const float>(take.normals[f]) : std::span<const float>(), out);
    bytes += static_cast<double>(b.positions_bytes + b.normals_bytes);
    frames += 1.0;
  });
  state.counters["bytes_per_frame"] = bytes / std::max(frames, 1.0);
}

void BM_DecodeCompressed(benchmark::State& state) {
  const DeformedTake& take = deformed_take();
  const bool with_normals = state.range(0) != 0;
  const int v = take.model.vertex_count();
  const std::vector<uint32_t> order = subscriber::compressed_vertex_order(take.model.reference_vertices);
  subscriber::CompressedVertexEncoder encoder(v, order);
  // The whole take coded once, in stream order.
  struct Coded {
    std::vector<unsigned char> bytes;
    subscriber::CompressedBlocks sizes;
  };
  std::vector<Coded> coded;
  for (size_t f = 0; f < take.positions.size(); ++f) {
    Coded c;
    c.bytes.resize(encoder.max_bytes(with_normals));
    c.sizes = encoder.encode(static_cast<uint32_t>(f), take.positions[f], with_normals ? std::span<const float>(take.normals[f]) : std::span<const float>(), c.bytes);
    coded.push_back(std::move(c));
  }
  subscriber::CompressedVertexDecoder decoder(v, order);
  std::vector<float> positions(3 * static_cast<size_t>(v)), normals(positions.size());
  timed(state, coded.size(), [&](size_t f) {
    const Coded& c = coded[f];
    decoder.decode(std::span(c.bytes).first(c.sizes.positions_bytes), std::span(c.bytes).subspan(c.sizes.positions_bytes, c.sizes.normals_bytes),
                   c.sizes.key, positions, with_normals ? std::span<float>(normals) : std::span<float>());
    benchmark::DoNotOptimize(positions.data());
  });
}

BENCHMARK(BM_FitPartsOnly)->Unit(benchmark::kMicrosecond)->MinTime(2.0);
BENCHMARK(BM_EvaluateParameters)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond)->MinTime(2.0);
BENCHMARK(BM_EncodeDecodeParameterBlock)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_EncodeCompressed)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond)->MinTime(2.0);
BENCHMARK(BM_DecodeCompressed)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond)->MinTime(2.0);

}  // namespace
}  // namespace skinstream

BENCHMARK_MAIN();
