#include "server/pipeline/deform_workers.h"

#include <chrono>

namespace skinstream::server {
namespace {

struct Range {
  int begin, end;
};
Range share(int count, int index, int parts) {
  return {static_cast<int>(static_cast<long>(count) * index / parts), static_cast<int>(static_cast<long>(count) * (index + 1) / parts)};
}

}  // namespace

DeformWorkers::DeformWorkers(MeshDeformer& deformer, int threads)
    : deformer_(deformer), threads_(std::max(1, threads)), barrier_(std::max(1, threads)) {
  for (int i = 1; i < threads_; ++i) workers_.emplace_back([this, i] { work(i); });
}

DeformWorkers::~DeformWorkers() {
  stopping_.store(true);
  if (!workers_.empty()) barrier_.arrive_and_wait();  // releases the workers waiting for a frame
  for (std::thread& t : workers_) t.join();
}

void DeformWorkers::run(std::span<float> positions, std::span<float> normals) {
  positions_ = positions;
  normals_ = normals;
  if (!workers_.empty()) barrier_.arrive_and_wait();  // start
  stage_range(0);
}

void DeformWorkers::work(int index) {
  for (;;) {
    barrier_.arrive_and_wait();  // start of a frame (or stop)
    if (stopping_.load()) return;
    stage_range(index);
  }
}

// Every participant runs every stage on its own range; the barriers keep the stages in order
// because vertices read other ranges' clusters and normals read other ranges' vertices.
void DeformWorkers::stage_range(int index) {
  const Range clusters = {deformer_.balanced_cluster_split(index, threads_), deformer_.balanced_cluster_split(index + 1, threads_)};
  const Range vertices = {deformer_.balanced_vertex_split(index, threads_), deformer_.balanced_vertex_split(index + 1, threads_)};
  const Range vertex_normals = share(deformer_.vertex_count(), index, threads_);
  const bool single = workers_.empty();
  const auto start = std::chrono::steady_clock::now();
  deformer_.deform_clusters(clusters.begin, clusters.end);
  if (!single) barrier_.arrive_and_wait();  // vertices read other ranges' clusters
  deformer_.blend_vertices(vertices.begin, vertices.end, positions_);
  if (!normals_.empty()) {
    if (!single) barrier_.arrive_and_wait();
    if (index == 0) deform_ns_ = std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - start).count();
    deformer_.vertex_normals(vertex_normals.begin, vertex_normals.end, positions_, normals_);
  }
  if (!single) barrier_.arrive_and_wait();  // frame done
  if (index == 0) {
    const int64_t total = std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - start).count();
    if (normals_.empty()) deform_ns_ = total;
    normals_ns_ = normals_.empty() ? 0 : total - deform_ns_;
  }
}

}  // namespace skinstream::server
