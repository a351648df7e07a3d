#pragma once
// The per-frame job of section 5.3 over the whole detailed mesh: fits every part to the filled
// markers (rigid by Horn, quadratic by eq. 6, RBF residual by eq. 7), then moves each vertex by
// eq. 8 in every part that influences it and blends them by eq. 9, and computes vertex normals.
//
// Split in stages so a caller with threads can share the work out by ranges (core/ has no
// threads itself): solve_parts() once, then rbf_residuals() over disjoint cluster ranges, then
// deform_vertices() over vertex ranges, then face_normals() over face ranges, then
// vertex_normals() over vertex ranges; each stage reads what the one before wrote.
// Buffers are sized at construction; no stage allocates.

#include <memory>
#include <span>
#include <vector>

#include "core/capture.h"
#include "core/deform/deformation_model.h"
#include "core/deform/part_deformation.h"
#include "core/subject_model.h"

namespace skinstream {

class MeshDeformer {
 public:
  // The subject gives the markers' reference positions (the parts' rest state). Throws
  // std::invalid_argument when the model does not validate against the subject.
  MeshDeformer(const DeformationModel& model, const SubjectModel& subject,
               DeformationMode mode = DeformationMode::QuadraticRbf);
  ~MeshDeformer();
  MeshDeformer(const MeshDeformer&) = delete;
  MeshDeformer& operator=(const MeshDeformer&) = delete;

  // Fits every part to the markers (subject order, all present). Returns false, keeping the
  // previous fit, when the count is wrong or a marker is not finite.
  bool solve_parts(std::span<const Vec3> markers);

  // The RBF term of eq. 8 for the influences of clusters [begin, end) (a no-op in the modes
  // without RBF). Influences are grouped in clusters of nearby vertices of one part so that
  // only the centres within the kernel's support are summed.
  void rbf_residuals(int begin, int end);
  int rbf_cluster_count() const;
  // Vertices [begin, end) into `positions` (3 floats per vertex, the whole mesh's buffer).
  void deform_vertices(int begin, int end, std::span<float> positions) const;
  // Face normals of faces [begin, end) from the deformed positions (into an internal buffer).
  void face_normals(int begin, int end, std::span<const float> positions);
  // Unit vertex normals [begin, end) (3 floats per vertex) from the face normals.
  void vertex_normals(int begin, int end, std::span<float> normals) const;

  // All stages on the calling thread. `normals` may be empty (not wanted).
  bool deform(std::span<const Vec3> markers, std::span<float> positions, std::span<float> normals);

  // Where to cut the vertices into `parts` ranges of equal work (vertices in big parts with the
  // RBF residual cost more than others): the start of range `index` (index == parts: the end).
  int balanced_vertex_split(int index, int parts) const;
  // The same for the clusters of rbf_residuals().
  int balanced_cluster_split(int index, int parts) const;

  int vertex_count() const;
  int face_count() const;
  DeformationMode mode() const;
  // Heap bytes held by the runtime state (precomputed per-vertex data, parts, normals scratch).
  size_t memory_bytes() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace skinstream
