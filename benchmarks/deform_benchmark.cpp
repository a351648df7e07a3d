// Per-frame cost of the skin deformation (section 5.3) of the ~53,500-vertex subdivided body from
// ~350 markers in ~17 parts, normals included: on one core, and split over threads exactly as
// the daemon runs it (server/pipeline/deform_workers). A plain copy of the same output bytes (positions + normals) is the physical
// floor: writing the buffer cannot be faster than memory bandwidth allows.
// The subject and frames: benchmarks/punch_scenario.h.
//   build/bin/deform_benchmark --benchmark_format=json
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <thread>

#include "benchmarks/punch_scenario.h"
#include "core/deform/mesh_deformer.h"
#include "server/pipeline/deform_cpus.h"
#include "server/pipeline/deform_workers.h"

namespace skinstream {
namespace {

void report(benchmark::State& state, std::vector<double>& micros, const MeshDeformer& deformer) {
  std::sort(micros.begin(), micros.end());
  auto pct = [&](double q) { return micros[std::min(micros.size() - 1, static_cast<size_t>(q * micros.size()))]; };
  state.counters["p50_us"] = pct(0.50);
  state.counters["p99_us"] = pct(0.99);
  state.counters["max_us"] = micros.back();
  state.counters["vertices"] = deformer.vertex_count();
  state.counters["parts"] = scenario().model.part_count();
  state.counters["markers"] = scenario().subject.marker_count();
  state.counters["runtime_bytes"] = static_cast<double>(deformer.memory_bytes());
}

// Argument: the mode (0 rigid, 1 quadratic, 2 rigid + RBF, 3 full), to see where time goes.
void BM_DeformOneThread(benchmark::State& state) {
  const Scenario& s = scenario();
  MeshDeformer deformer(s.model, s.subject, static_cast<DeformationMode>(state.range(0)));
  std::vector<float> positions(static_cast<size_t>(deformer.vertex_count()) * 3), normals(positions.size());
  std::vector<double> micros;
  micros.reserve(1 << 16);
  // Each frame's fastest run: the frame's own work, with the machine's interruptions filtered out
  // (every frame runs several times). Their spread says whether the tail is heavier frames or noise.
  std::vector<double> fastest(s.frames.size(), 1e300);
  size_t frame = 0;
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    deformer.deform(s.frames[frame], positions, normals);
    micros.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count());
    fastest[frame] = std::min(fastest[frame], micros.back());
    benchmark::DoNotOptimize(positions.data());
    frame = (frame + 1) % s.frames.size();
  }
  report(state, micros, deformer);
  if (micros.size() >= 2 * s.frames.size()) {  // every frame ran at least twice
    std::sort(fastest.begin(), fastest.end());
    state.counters["frame_work_p50_us"] = fastest[fastest.size() / 2];
    state.counters["frame_work_max_us"] = fastest.back();
  }
}

// The daemon's split (server/pipeline/deform_workers): the calling thread and persistent
// workers taking small tasks of each stage from shared counters. Argument: threads.
void BM_DeformThreads(benchmark::State& state) {
  const Scenario& s = scenario();
  MeshDeformer deformer(s.model, s.subject);
  std::vector<float> positions(static_cast<size_t>(deformer.vertex_count()) * 3), normals(positions.size());
  server::DeformWorkers workers(deformer, static_cast<int>(state.range(0)));
  std::vector<double> micros;
  micros.reserve(1 << 16);
  size_t frame = 0;
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    workers.run(s.frames[frame], positions, normals);
    micros.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count());
    benchmark::DoNotOptimize(positions.data());
    frame = (frame + 1) % s.frames.size();
  }
  report(state, micros, deformer);
}

// Runs `deform(frame markers)` once per frame of the take at 120 Hz, timing each run but not
// the wait before it, and returns the times in microseconds.
template <typename Deform>
std::vector<double> deform_at_120hz(benchmark::State& state, Deform&& deform) {
  const Scenario& s = scenario();
  std::vector<double> micros;
  micros.reserve(1 << 14);
  const auto period = std::chrono::nanoseconds(1'000'000'000 / 120);
  auto due = std::chrono::steady_clock::now();
  size_t frame = 0;
  for (auto _ : state) {
    state.PauseTiming();
    due += period;
    std::this_thread::sleep_until(due);
    state.ResumeTiming();
    const auto start = std::chrono::steady_clock::now();
    deform(s.frames[frame]);
    micros.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count());
    frame = (frame + 1) % s.frames.size();
  }
  return micros;
}

// One thread fed at 120 Hz: against BM_DeformOneThread, what the 7 ms between frames costs a
// frame with no thread to wake. On this shared machine it is the caches: spinning between
// frames instead of sleeping gave the same median (see the README).
void BM_DeformOneThreadAt120Hz(benchmark::State& state) {
  const Scenario& s = scenario();
  MeshDeformer deformer(s.model, s.subject);
  std::vector<float> positions(static_cast<size_t>(deformer.vertex_count()) * 3), normals(positions.size());
  std::vector<double> micros = deform_at_120hz(state, [&](const std::vector<Vec3>& markers) {
    deformer.deform(markers, positions, normals);
    benchmark::DoNotOptimize(positions.data());
  });
  report(state, micros, deformer);
}

// Two threads fed at 120 Hz as the daemon is, not back to back: between frames the worker
// sleeps, and each frame pays for waking it unless it anticipated the frame. Argument 0: the
// worker woken by run() (deform_spin_lead_us 0); 1: a 1000 us spin lead (the daemon's
// default); 2: the lead and both threads pinned to the last two CPUs (deform_cpus "0,1" on a
// 2-core machine, where "auto" does not pin).
void BM_DeformTwoThreadsAt120Hz(benchmark::State& state) {
  const Scenario& s = scenario();
  MeshDeformer deformer(s.model, s.subject);
  std::vector<float> positions(static_cast<size_t>(deformer.vertex_count()) * 3), normals(positions.size());
  server::DeformWorkerOptions options;
  options.threads = 2;
  const std::vector<int> allowed = server::allowed_cpus();
  if (state.range(0) >= 1) options.spin_lead = std::chrono::microseconds(1000);
  if (state.range(0) == 2 && allowed.size() >= 2) {
    options.cpus = {allowed[allowed.size() - 2], allowed.back()};
    server::pin_this_thread(options.cpus[0]);
  }
  std::vector<double> micros;
  {
    server::DeformWorkers workers(deformer, options);
    micros = deform_at_120hz(state, [&](const std::vector<Vec3>& markers) {
      workers.run(markers, positions, normals);
      benchmark::DoNotOptimize(positions.data());
    });
  }
  state.counters["pinned"] = options.cpus.empty() ? 0 : 1;
  if (!options.cpus.empty()) server::set_this_thread_cpus(allowed);  // the benchmarks after this one run unpinned
  report(state, micros, deformer);
}

void BM_SolvePartsOnly(benchmark::State& state) {
  const Scenario& s = scenario();
  MeshDeformer deformer(s.model, s.subject);
  size_t frame = 0;
  for (auto _ : state) {
    deformer.solve_parts(s.frames[frame]);
    frame = (frame + 1) % s.frames.size();
  }
}

// The floor: copying the bytes one frame publishes (positions + normals, float32).
void BM_CopyOutputBuffer(benchmark::State& state) {
  const Scenario& s = scenario();
  const size_t bytes = static_cast<size_t>(s.model.vertex_count()) * 6 * sizeof(float);
  std::vector<char> from(bytes, 1), to(bytes);
  for (auto _ : state) {
    std::memcpy(to.data(), from.data(), bytes);
    benchmark::DoNotOptimize(to.data());
    benchmark::ClobberMemory();
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations() * bytes));
}

BENCHMARK(BM_DeformOneThread)->Arg(3)->Arg(1)->Arg(0)->Unit(benchmark::kMicrosecond)->MinTime(3.0)->UseRealTime();
BENCHMARK(BM_DeformThreads)->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond)->MinTime(3.0)->UseRealTime();
BENCHMARK(BM_DeformOneThreadAt120Hz)->Unit(benchmark::kMicrosecond)->Iterations(2400)->UseRealTime();  // 20 s
BENCHMARK(BM_DeformTwoThreadsAt120Hz)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond)->Iterations(2400)->UseRealTime();  // 20 s each
BENCHMARK(BM_SolvePartsOnly)->Unit(benchmark::kMicrosecond)->MinTime(1.0);
BENCHMARK(BM_CopyOutputBuffer)->Unit(benchmark::kMicrosecond)->MinTime(1.0);

}  // namespace
}  // namespace skinstream

BENCHMARK_MAIN();
