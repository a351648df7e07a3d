// Per-frame cost of the online gap filler (relabel + fill), the 120 Hz hot path.
//   41 markers: the CMU 85_12 capture with seeded gaps (about 7% of samples missing).
//   350 markers, grid: a dense grid over a deforming cylinder (14 x 25), same gap plan.
//   350 markers, synthetic punch: the generator's 5 s punching take as a capture system
//     delivers it (occlusion, broken and mislabelled trajectories, unlabelled fragments,
//     ghosts), subject trained on its 20 s range-of-motion take.
// Argument regions: 1 with each missing marker's regional PCA opinion (the default), 0 without.
// Punch as in the paper: the same take filled with section 4.3's opinions alone (the neighbours'
// PCA estimates averaged plainly, eq. 2 where none speaks; no variance weighting, carry, regions
// or online checks): what this machine spends on the method itself, before what was added to it.
// Each iteration fills one frame; p50/p99 come from the per-frame times of the run: wall
// clock (p50_us, p99_us: what the daemon's frame waits) and the thread's CPU time (cpu_p50_us,
// cpu_p99_us: the filler's own work, without the time the OS gave other processes, which is
// what tells two builds apart on a shared, loaded machine).
//   build/bin/fill_benchmark --benchmark_format=json
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <ctime>

#include "core/capture_filler.h"
#include "core/evaluation/gap_plan.h"
#include "core/gap_filler.h"
#include "core/offline/subject_builder.h"
#include "core/synth/synth_capture.h"
#include "protocol/files/capture_file.h"
#include "protocol/offline/makehuman.h"
#include "support/synthetic_limb.h"

namespace skinstream {
namespace {

struct Scenario {
  SubjectModel model;
  Capture gapped;
};

Scenario make_scenario(const Capture& full) {
  Scenario s;
  const int cut = full.frame_count / 2;
  std::vector<int> all(full.point_count());
  for (int p = 0; p < full.point_count(); ++p) all[p] = p;
  s.model = build_subject(full.select(all, 0, cut), {});
  const Capture test = full.select(all, cut, full.frame_count - cut);
  GapPlanOptions plan;
  plan.seed = 7;
  s.gapped = apply_gaps(test, plan_gaps(test, plan));
  return s;
}

double thread_cpu_micros() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return 1e6 * static_cast<double>(t.tv_sec) + 1e-3 * static_cast<double>(t.tv_nsec);
}

void run(benchmark::State& state, const Scenario& s, GapFillerOptions options) {
  const int n = s.model.marker_count();
  GapFiller filler(s.model, options);
  const std::vector<int> channel_of = map_channels_to_markers(s.model, s.gapped);
  std::vector<int> free_channels;
  for (int c = 0; c < s.gapped.point_count(); ++c)
    if (std::find(channel_of.begin(), channel_of.end(), c) == channel_of.end()) free_channels.push_back(c);
  std::vector<Vec3> in(n), out(n), free_points;
  std::vector<int> free_ids;
  free_points.reserve(free_channels.size());
  free_ids.reserve(free_channels.size());
  std::vector<MarkerStatus> status(n);
  std::vector<double> micros, cpu_micros;
  micros.reserve(1 << 20);
  cpu_micros.reserve(1 << 20);
  long missing = 0;
  int frame = 0;
  for (auto _ : state) {
    for (int i = 0; i < n; ++i) in[i] = s.gapped.at(frame, channel_of[i]);
    free_points.clear();
    free_ids.clear();
    for (int c : free_channels)
      if (s.gapped.present(frame, c)) {
        free_points.push_back(s.gapped.at(frame, c));
        free_ids.push_back(c);
      }
    const double cpu_start = thread_cpu_micros();
    const auto start = std::chrono::steady_clock::now();
    const FillStats stats = filler.run({in, free_points, free_ids}, {out, status});
    micros.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count());
    cpu_micros.push_back(thread_cpu_micros() - cpu_start);
    benchmark::DoNotOptimize(out.data());
    missing += stats.filled + stats.held;
    frame = (frame + 1) % s.gapped.frame_count;
    if (frame == 0) filler.reset();
  }
  std::sort(micros.begin(), micros.end());
  std::sort(cpu_micros.begin(), cpu_micros.end());
  auto pct = [](const std::vector<double>& v, double q) { return v[std::min(v.size() - 1, static_cast<size_t>(q * v.size()))]; };
  state.counters["p50_us"] = pct(micros, 0.50);
  state.counters["p99_us"] = pct(micros, 0.99);
  state.counters["max_us"] = micros.back();
  state.counters["cpu_p50_us"] = pct(cpu_micros, 0.50);
  state.counters["cpu_p99_us"] = pct(cpu_micros, 0.99);
  state.counters["markers"] = n;
  state.counters["missing_per_frame"] = static_cast<double>(missing) / micros.size();
}

GapFillerOptions with_regions(const benchmark::State& state) {
  GapFillerOptions options;
  options.use_regions = state.range(0) != 0;
  return options;
}

void BM_Fill41MarkersCmu(benchmark::State& state) {
  static const Scenario s = make_scenario(read_capture(std::string(SKINSTREAM_SHARED_DIR) + "/data/captures/cmu/85_12.c3d"));
  run(state, s, with_regions(state));
}

void BM_Fill350MarkersDense(benchmark::State& state) {
  static const Scenario s = [] {
    test::LimbOptions o;
    o.around = 14;
    o.along = 25;
    o.radius = 150.0;
    o.length = 1600.0;
    o.frames = 2400;
    return make_scenario(test::make_limb_capture(o));
  }();
  run(state, s, with_regions(state));
}

const Scenario& synthetic_punch() {
  static const Scenario s = [] {
    const Body body = load_makehuman(std::string(SKINSTREAM_SHARED_DIR) + "/data/meshes/makehuman");
    synth::SynthOptions take;
    take.motion = "punch";
    synth::SynthOptions rom;
    rom.motion = "rom";
    rom.seconds = 20.0;
    Scenario out;
    out.model = build_subject(synth::generate(body, rom).truth, {});
    out.gapped = synth::generate(body, take).capture;
    return out;
  }();
  return s;
}

void BM_Fill350MarkersSyntheticPunch(benchmark::State& state) { run(state, synthetic_punch(), with_regions(state)); }

void BM_Fill350MarkersSyntheticPunchAsInThePaper(benchmark::State& state) {
  GapFillerOptions paper;
  paper.weight_by_variance = false;
  paper.fuse_rigid = paper.carry_from_gap_start = paper.use_regions = paper.learn_regions = paper.calibrate_rings = false;
  run(state, synthetic_punch(), paper);
}

BENCHMARK(BM_Fill350MarkersSyntheticPunch)->ArgName("regions")->Arg(1)->Arg(0)->Unit(benchmark::kMicrosecond)->MinTime(2.0);
BENCHMARK(BM_Fill350MarkersSyntheticPunchAsInThePaper)->Unit(benchmark::kMicrosecond)->MinTime(2.0);
BENCHMARK(BM_Fill41MarkersCmu)->ArgName("regions")->Arg(1)->Arg(0)->Unit(benchmark::kMicrosecond)->MinTime(2.0);
BENCHMARK(BM_Fill350MarkersDense)->ArgName("regions")->Arg(1)->Arg(0)->Unit(benchmark::kMicrosecond)->MinTime(2.0);

}  // namespace
}  // namespace skinstream

BENCHMARK_MAIN();
