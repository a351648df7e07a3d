#include "server/pipeline/deform_workers.h"

#include <algorithm>
#include <chrono>
#include <numeric>
#include <string>

#include "server/pipeline/deform_cpus.h"
#include "server/thread_name.h"

namespace skinstream::server {
namespace {

constexpr int kClustersPerTask = 8;  // ~6 us of work: small enough to share, large enough to count
constexpr int kVertexTasks = 32;     // per vertex stage, at most (chunks are whole normal groups)
constexpr int kMaxTasks = 0xffff;    // per stage: tasks are counted in 16 bits
// A woken worker spins this long for its frame before it sleeps again: longer than the fill
// that get_ready() overlaps, short enough not to hold a core when frames stop.
constexpr std::chrono::microseconds kReadySpin{2000};
// Intervals between runs longer than this are pauses of the source, not its frame rate.
constexpr int64_t kLongestFrameIntervalNs = 100'000'000;

// A stage's Stage::left: the generation, then the first and one past the last task not taken.
uint64_t pack_left(uint32_t generation, uint32_t front, uint32_t back) {
  return (static_cast<uint64_t>(generation) << 32) | (front << 16) | back;
}

// Waiting for another thread's short task: spin a little, then give the core away.
void pause(int& spins) {
  if (++spins < 256) {
#if defined(__x86_64__) || defined(__i386__)
    __builtin_ia32_pause();
#endif
  } else {
    std::this_thread::yield();
  }
}

}  // namespace

DeformWorkers::DeformWorkers(MeshDeformer& deformer, const DeformWorkerOptions& options)
    : deformer_(deformer),
      threads_(std::max(1, options.threads)),
      spin_lead_(std::max(options.spin_lead, std::chrono::microseconds(0))) {
  const int parts = deformer_.part_count();
  auto fit_cost = [&](int p) { return static_cast<int64_t>(deformer_.part_member_count(p)) * deformer_.part_member_count(p) * deformer_.part_member_count(p); };
  part_order_.resize(static_cast<size_t>(parts));
  std::iota(part_order_.begin(), part_order_.end(), 0);
  std::stable_sort(part_order_.begin(), part_order_.end(), [&](int a, int b) { return fit_cost(a) > fit_cost(b); });
  part_fitted_ = std::make_unique<std::atomic<uint32_t>[]>(static_cast<size_t>(parts));
  for (int p = 0; p < parts; ++p) part_fitted_[p].store(0);

  // Cluster tasks: the clusters of the lower half of the vertex sequence from the front, those
  // of the upper half from the back (the calling thread takes from the front, the workers from
  // the back, as in the vertex stages: each mostly blends results it wrote itself). From either
  // end the parts with the cheapest fit come first, so that a thread reaches a part's clusters
  // when its fit is most likely done; the largest part's meet in the middle.
  // A stage counts its tasks in 16 bits: a mesh far beyond ~100k vertices gets larger chunks.
  // (Each part may add two short chunks: room is left for those and for the fits.)
  const int clusters_per_task = std::max(kClustersPerTask, deformer_.cluster_count() / (kMaxTasks - 3 * parts - 1) + 1);
  std::vector<ClusterChunk> upper_chunks;
  for (auto it = part_order_.rbegin(); it != part_order_.rend(); ++it)
    for (int c = 0; c < deformer_.cluster_count();) {
      if (deformer_.cluster_part(c) != *it) {
        ++c;
        continue;
      }
      const int begin = c;
      const bool upper = deformer_.cluster_in_upper_half(c);
      while (c < deformer_.cluster_count() && deformer_.cluster_part(c) == *it &&
             deformer_.cluster_in_upper_half(c) == upper && c - begin < clusters_per_task)
        ++c;
      (upper ? upper_chunks : cluster_chunks_).push_back({*it, begin, c});
    }
  cluster_chunks_.insert(cluster_chunks_.end(), upper_chunks.rbegin(), upper_chunks.rend());
  fits_and_clusters_.tasks = static_cast<uint32_t>(parts + cluster_chunks_.size());
  fits_and_clusters_.leading = static_cast<uint32_t>(parts);  // the fits lead, taken by all from the front
  const int group = deformer_.normal_group_size();  // chunks of whole groups: no normal computed twice
  vertex_chunk_ = std::max(1, (deformer_.vertex_count() + kVertexTasks * group - 1) / (kVertexTasks * group)) * group;
  vertices_.tasks = normals_stage_.tasks =
      static_cast<uint32_t>((deformer_.vertex_count() + vertex_chunk_ - 1) / vertex_chunk_);
  for (int i = 1; i < threads_; ++i) {
    workers_.emplace_back([this, name = options.thread_name + "-" + std::to_string(i)] {
      name_this_thread(name);
      work();
    });
    if (static_cast<int>(options.cpus.size()) == threads_ && !set_thread_cpus(workers_.back(), {options.cpus[i]}))
      ++unpinned_workers_;
  }
}

DeformWorkers::~DeformWorkers() {
  stopping_.store(true);
  generation_.fetch_add(1);
  wake_.fetch_add(1);
  wake_.notify_all();
  for (std::thread& t : workers_) t.join();
}

void DeformWorkers::reset(Stage& stage, uint32_t generation, bool skip) {
  stage.done.store(skip ? stage.tasks : 0, std::memory_order_relaxed);
  stage.left.store(pack_left(generation, skip ? stage.tasks : 0, stage.tasks), std::memory_order_release);
}

bool DeformWorkers::run(std::span<const Vec3> markers, std::span<float> positions, std::span<float> normals) {
  if (!deformer_.accepts(markers)) return false;
  const auto start = std::chrono::steady_clock::now();
  deformer_.solve_skeleton(markers);  // before the parts are shared out: each reads its segment's motion
  expect_next_run(start);
  const uint32_t generation = generation_.load(std::memory_order_relaxed) + 1;
  markers_ = markers;
  positions_ = positions;
  normals_ = normals;
  fits_only_ = positions.empty();  // seen by the workers through the generation's release below
  reset(fits_and_clusters_, generation, false);
  reset(vertices_, generation, fits_only_);
  reset(normals_stage_, generation, fits_only_ || normals.empty());
  generation_.store(generation, std::memory_order_release);
  get_ready();

  run_frame(generation, &start);
  normals_ns_ = normals.empty() ? 0 : std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - start).count() - deform_ns_;
  return true;
}

void DeformWorkers::get_ready() {
  if (workers_.empty()) return;
  wake_.fetch_add(1, std::memory_order_release);
  wake_.notify_all();  // no system call unless a worker sleeps
}

// The interval between runs, smoothed over about 8 runs so that one late frame moves the
// estimate by an eighth of its lateness.
void DeformWorkers::expect_next_run(std::chrono::steady_clock::time_point start) {
  const int64_t now = std::chrono::duration_cast<std::chrono::nanoseconds>(start.time_since_epoch()).count();
  const int64_t interval = now - last_run_ns_;
  last_run_ns_ = now;
  if (interval <= 0 || interval > kLongestFrameIntervalNs) {
    run_interval_ns_ = 0;  // a pause: no estimate until two runs come close together again
  } else {
    run_interval_ns_ = run_interval_ns_ == 0 ? interval : run_interval_ns_ + (interval - run_interval_ns_) / 8;
  }
  next_run_due_ns_.store(run_interval_ns_ == 0 ? 0 : now + run_interval_ns_, std::memory_order_relaxed);
}

// Sleeps until woken, then spins for a new generation and runs it. After a frame it
// anticipates the next (see the header) or sleeps again; a spin that finds no frame within
// kReadySpin of when one was due sleeps too. `wake_` is read before the generation each time
// round: a run() published after that read bumps `wake_` past it, so no sleep misses its frame.
void DeformWorkers::work() {
  using Clock = std::chrono::steady_clock;
  uint32_t seen_wake = 0, seen_generation = 0;
  for (;;) {
    wake_.wait(seen_wake, std::memory_order_acquire);
    auto give_up = Clock::now() + kReadySpin;
    for (int spins = 0;; pause(spins)) {
      const uint32_t wake = wake_.load(std::memory_order_acquire);
      const uint32_t generation = generation_.load(std::memory_order_acquire);
      if (stopping_.load()) return;
      if (generation != seen_generation) {
        seen_generation = generation;
        run_frame(generation, nullptr);
        const int64_t due_ns = next_run_due_ns_.load(std::memory_order_relaxed);
        if (spin_lead_.count() > 0 && due_ns > 0) {
          const Clock::time_point due{std::chrono::nanoseconds(due_ns)};
          std::this_thread::sleep_until(due - spin_lead_);  // returns at once when that has passed
          give_up = std::max(due, Clock::now()) + kReadySpin;
        } else {
          give_up = Clock::now();  // one more look at `wake_`, then sleep
        }
        spins = 0;
        continue;
      } else if (spins % 64 != 63 || Clock::now() < give_up) {
        continue;
      }
      seen_wake = wake;
      break;
    }
  }
}

// One participant's share of a frame: the calling thread's (which times the stages from
// `start`) or a worker's, which leaves as soon as it sees a later generation.
// Every stage after the fits is taken from both ends, the calling thread from the front and the
// workers from the back. With two threads each then blends mostly the cluster results it wrote
// (the clusters of the lower half of the vertex sequence come first, see the constructor) and
// computes the normals of the vertices it blended, whose neighbours (the sequence's halves are
// spatially compact) it also blended. Reading the other core's writes made the normals stage
// half as dear again in total (measured with stage timers); on this host, in stretches when
// moving data between the two vCPUs is slow, taking the clusters this way cut the two-thread
// median from 1.10 to 1.00 ms, and spatial halves in place of halves of the numbering from 0.99
// to 0.88 ms.
void DeformWorkers::run_frame(uint32_t generation, const std::chrono::steady_clock::time_point* start) {
  const End end = start ? End::Front : End::Back;
  // Fits first, largest part first, from the front by everyone (Stage::leading); then the
  // clusters from this participant's end.
  if (!run_stage(fits_and_clusters_, generation, end, [&](uint32_t task) { fit_or_cluster_task(task, generation); }))
    return;
  if (!run_stage(vertices_, generation, end, [&](uint32_t task) {
        deformer_.blend_vertices(static_cast<int>(task) * vertex_chunk_, static_cast<int>(task + 1) * vertex_chunk_, positions_);
      }))
    return;
  if (start) deform_ns_ = std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - *start).count();
  run_stage(normals_stage_, generation, end, [&](uint32_t task) {
    deformer_.vertex_normals(static_cast<int>(task) * vertex_chunk_, static_cast<int>(task + 1) * vertex_chunk_, positions_, normals_);
  });
}

// Takes tasks of this generation until none are left, then waits for the ones others took.
// Returns false when the frame has moved on (only a late worker sees that).
template <typename Task>
bool DeformWorkers::run_stage(Stage& stage, uint32_t generation, End end, Task&& task) {
  uint64_t left = stage.left.load(std::memory_order_acquire);
  for (;;) {
    if (static_cast<uint32_t>(left >> 32) != generation) return false;
    const uint32_t front = static_cast<uint32_t>(left >> 16) & 0xffff, back = static_cast<uint32_t>(left) & 0xffff;
    if (front >= back) break;
    const End take = front < stage.leading ? End::Front : end;
    const uint32_t index = take == End::Front ? front : back - 1;
    const uint64_t after = take == End::Front ? pack_left(generation, front + 1, back) : pack_left(generation, front, back - 1);
    if (!stage.left.compare_exchange_weak(left, after, std::memory_order_acquire, std::memory_order_acquire)) continue;
    task(index);
    stage.done.fetch_add(1, std::memory_order_release);
    left = stage.left.load(std::memory_order_acquire);
  }
  int spins = 0;
  while (stage.done.load(std::memory_order_acquire) < stage.tasks) {
    if (static_cast<uint32_t>(stage.left.load(std::memory_order_acquire) >> 32) != generation) return false;
    pause(spins);
  }
  return true;
}

// Tasks [0, parts): fit part part_order_[task]; then cluster chunks, each after its part's fit.
void DeformWorkers::fit_or_cluster_task(uint32_t task, uint32_t generation) {
  const uint32_t parts = static_cast<uint32_t>(part_order_.size());
  if (task < parts) {
    const int part = part_order_[task];
    deformer_.solve_part(part, markers_);
    part_fitted_[part].store(generation, std::memory_order_release);
    return;
  }
  if (fits_only_) return;  // the parameters alone were wanted
  const ClusterChunk& chunk = cluster_chunks_[task - parts];
  int spins = 0;
  // Every fit task was taken before any cluster task, so the part's fit is under way.
  while (part_fitted_[chunk.part].load(std::memory_order_acquire) != generation) pause(spins);
  deformer_.deform_clusters(chunk.begin, chunk.end);
}

}  // namespace skinstream::server
