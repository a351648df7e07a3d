#pragma once
// Shares the mesh deformation of one frame out over threads: the calling (pipeline) thread and
// `threads - 1` persistent workers. Each stage of MeshDeformer is cut into small tasks that
// whoever is running takes from a shared counter, so a worker the OS has not scheduled yet
// holds nobody up: the calling thread then does the frame alone (on a loaded stage machine
// that is the difference between a late frame and a merely slower one).
//
// Stages, in order: part fits and clusters (a cluster waits only for its own part's fit, so
// the largest part's fit overlaps the other parts' clusters), then eq. 9 per vertex, then the
// vertex normals. After the fits, the calling thread works from the front of each stage (the
// lower half of the deformer's vertex sequence) and the workers from the back, so that each
// mostly reads what it wrote itself. No thread is created and nothing is allocated per frame.
//
// Waking a sleeping worker costs the OS's wake-up latency inside the frame: on a virtual
// machine whose idle core has halted, 0.09 ms at the median and more than a millisecond in
// the tail (measured in skinstreamd under skinstream-bench). Frames come at a steady rate, so a
// worker can anticipate: after a frame it sleeps until `spin_lead` before the next one is due
// (from the interval between runs) and spins from then on. The lead is a trade of CPU for
// latency: 0 sleeps until woken (get_ready() and run() wake it), a lead longer than the frame
// interval never sleeps while frames keep coming.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "core/deform/mesh_deformer.h"

namespace skinstream::server {

struct DeformWorkerOptions {
  int threads = 1;  // the calling thread included
  // How long before the next frame is due a worker starts to spin for it (see above).
  std::chrono::microseconds spin_lead{0};
  // Empty, or one CPU per thread: index 0 is the calling thread's (its owner pins it, with
  // pin_this_thread from deform_cpus.h), the others the workers', pinned as they are made.
  std::vector<int> cpus;
  std::string thread_name = "deform";  // worker i is named thread_name-i
};

class DeformWorkers {
 public:
  DeformWorkers(MeshDeformer& deformer, const DeformWorkerOptions& options);
  DeformWorkers(MeshDeformer& deformer, int threads) : DeformWorkers(deformer, DeformWorkerOptions{threads, {}, {}}) {}
  ~DeformWorkers();
  DeformWorkers(const DeformWorkers&) = delete;
  DeformWorkers& operator=(const DeformWorkers&) = delete;

  // Fits the parts to `markers` and deforms into `positions` (3V floats) and, when `normals`
  // is not empty, `normals` (3V). With `positions` empty, only fits the parts (the parameters,
  // MeshDeformer::parameters()): the clusters, the blend and the normals are skipped. Returns
  // false, changing nothing, when the deformer does not accept the markers (wrong count, a
  // marker not finite).
  bool run(std::span<const Vec3> markers, std::span<float> positions, std::span<float> normals);
  // Says a run() is coming soon (the caller is about to fill the frame): a sleeping worker
  // wakes now, and its wake-up overlaps the caller's work instead of the deformation.
  void get_ready();
  int threads() const { return threads_; }
  // The workers the OS refused to pin to their CPU (0 when none were to be pinned).
  int unpinned_workers() const { return unpinned_workers_; }
  // Wall time of the last run's stages, measured by the calling thread: fits to positions, and
  // normals.
  int64_t last_deform_ns() const { return deform_ns_; }
  int64_t last_normals_ns() const { return normals_ns_; }

 private:
  // One stage's tasks: `left` holds the frame's generation in its high 32 bits and the tasks
  // not yet taken, [front, back), in its low 32 (16 bits each), so a worker that wakes after its
  // frame ended can never take a task of the next one; `done` counts finished tasks. The first
  // `leading` tasks are taken from the front by every participant, whatever its end.
  struct alignas(64) Stage {  // own cache line: both threads hammer these counters
    std::atomic<uint64_t> left{0};
    std::atomic<uint32_t> done{0};
    uint32_t tasks = 0;
    uint32_t leading = 0;
  };
  struct ClusterChunk {
    int part, begin, end;
  };

  void work();
  void run_frame(uint32_t generation, const std::chrono::steady_clock::time_point* start);
  // Which end of a stage's tasks a participant takes from.
  enum class End { Front, Back };
  template <typename Task>
  bool run_stage(Stage& stage, uint32_t generation, End end, Task&& task);
  void reset(Stage& stage, uint32_t generation, bool skip);
  void expect_next_run(std::chrono::steady_clock::time_point start);
  void fit_or_cluster_task(uint32_t task, uint32_t generation);

  MeshDeformer& deformer_;
  int threads_;
  int unpinned_workers_ = 0;
  std::vector<int> part_order_;             // largest part first: its fit is the longest task
  std::vector<ClusterChunk> cluster_chunks_;  // the largest part's clusters last
  int vertex_chunk_ = 0;
  std::unique_ptr<std::atomic<uint32_t>[]> part_fitted_;  // the generation of each part's last fit

  Stage fits_and_clusters_, vertices_, normals_stage_;
  std::atomic<uint32_t> generation_{0};
  std::atomic<uint32_t> wake_{0};  // what sleeping workers wait on: bumped by get_ready(), run(), stop
  // When the next run() is expected (steady clock, ns; 0: no estimate yet), from the interval
  // between runs, smoothed.
  std::atomic<int64_t> next_run_due_ns_{0};
  int64_t last_run_ns_ = 0, run_interval_ns_ = 0;  // the calling thread's
  std::chrono::nanoseconds spin_lead_;
  std::atomic<bool> stopping_{false};
  // Set by run() before the generation is published, read by tasks after they take one.
  std::span<const Vec3> markers_;
  std::span<float> positions_, normals_;
  bool fits_only_ = false;  // this frame: the part fits alone
  std::vector<std::thread> workers_;
  int64_t deform_ns_ = 0, normals_ns_ = 0;
};

}  // namespace skinstream::server
