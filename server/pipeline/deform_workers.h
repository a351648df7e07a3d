#pragma once
// Shares the mesh deformation of one frame out over threads: the calling (pipeline) thread and
// `threads - 1` persistent workers, each taking its own cluster and vertex ranges, with a
// barrier between the stages of MeshDeformer (clusters -> vertices -> vertex normals). No
// thread is created per frame.

#include <atomic>
#include <barrier>
#include <cstdint>
#include <span>
#include <thread>
#include <vector>

#include "core/deform/mesh_deformer.h"

namespace skinstream::server {

class DeformWorkers {
 public:
  DeformWorkers(MeshDeformer& deformer, int threads);
  ~DeformWorkers();
  DeformWorkers(const DeformWorkers&) = delete;
  DeformWorkers& operator=(const DeformWorkers&) = delete;

  // Deforms into `positions` (3V floats) and, when `normals` is not empty, `normals` (3V).
  // Call solve_parts() on the deformer first. Runs on the calling thread plus the workers.
  void run(std::span<float> positions, std::span<float> normals);
  int threads() const { return threads_; }
  // Wall time of the last run's stages (measured by the calling thread, barriers included).
  int64_t last_deform_ns() const { return deform_ns_; }
  int64_t last_normals_ns() const { return normals_ns_; }

 private:
  void work(int index);
  void stage_range(int index);

  MeshDeformer& deformer_;
  int threads_;
  std::barrier<> barrier_;
  std::atomic<bool> stopping_{false};
  std::span<float> positions_, normals_;  // set before the start barrier, read after it
  std::vector<std::thread> workers_;
  int64_t deform_ns_ = 0, normals_ns_ = 0;
};

}  // namespace skinstream::server
