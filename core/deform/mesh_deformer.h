#pragma once
// The per-frame job of section 5.3 over the whole detailed mesh: fits every part to the filled
// markers (rigid by Horn, quadratic by eq. 6, RBF residual by eq. 7) into the frame's part
// parameters, then moves each vertex by eq. 8 in every part that influences it and blends them
// by eq. 9, and computes vertex normals (the MeshEvaluator, from the parameters alone: what a
// renderer receiving the parameters evaluates too).
//
// Split in stages so a caller with threads can share the work out by ranges (core/ has no
// threads itself): solve_part() for every part, then deform_clusters() over disjoint cluster
// ranges, then blend_vertices() over vertex ranges, then vertex_normals() over vertex ranges;
// each stage reads what the one before wrote (see MeshEvaluator for the vertex sequence). A
// caller that only wants the parameters stops after the fits.
// Buffers are sized at construction; no stage allocates.

#include <memory>
#include <span>
#include <vector>

#include "core/capture.h"
#include "core/deform/deformation_model.h"
#include "core/deform/evaluation_model.h"
#include "core/deform/mesh_evaluator.h"
#include "core/deform/part_deformation.h"
#include "core/deform/part_parameters.h"
#include "core/subject_model.h"

namespace skinstream {

struct PartModel;
class SkeletonSolver;

// From the subject's deformation model and its parts' offline data (in part order), rounded to
// float once here: what MeshDeformer evaluates with, and what the daemon sends parameter
// subscribers in the Model message.
EvaluationModel make_evaluation_model(const DeformationModel& model, const std::vector<PartModel>& parts);

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
  // The fit of the last solved frame, in float, as the evaluator uses it and the subscriber
  // protocol sends it; and the static data it is evaluated with.
  const FrameParameters& parameters() const;
  const EvaluationModel& evaluation_model() const;
  // The same in pieces, for callers that share the parts out over threads: whether the
  // markers can be used, then each part's fit (different parts may be solved concurrently;
  // the clusters of a part need that part's fit).
  bool accepts(std::span<const Vec3> markers) const;
  // A model with a skeleton (a sparse marker set's fitted body) poses it first, once per frame,
  // before any part is solved: every part takes its rigid transform from it. No-op otherwise.
  void solve_skeleton(std::span<const Vec3> markers);
  bool has_skeleton() const;
  const SkeletonSolver* skeleton() const;  // null without one
  void solve_part(int part, std::span<const Vec3> markers);
  int part_count() const;
  int part_member_count(int part) const;
  int cluster_part(int cluster) const;
  // Whether the cluster's influences are of vertices in the upper half of the vertex sequence
  // (slots [upper_half_slot(), vertex_count)); otherwise all are in the lower half. The
  // clusters of a part come lower half first. DeformWorkers gives the two halves to threads
  // that blend the same halves, so that eq. 9 mostly reads results its own core wrote.
  bool cluster_in_upper_half(int cluster) const;

  // Eq. 8 for the influences (vertex, part) of clusters [begin, end), each weighted by its
  // beta. Influences are grouped in clusters of nearby vertices of one part, evaluated in
  // vector lanes, so that only the RBF centres within the kernel's support are summed.
  void deform_clusters(int begin, int end);
  int cluster_count() const;
  // Eq. 9 for the vertices at slots [begin, end) of the sequence into `positions` (3 floats
  // per vertex, the whole mesh's buffer in mesh order): the sum of the vertex's weighted results
  // from deform_clusters().
  void blend_vertices(int begin, int end, std::span<float> positions) const;
  // Unit area-weighted vertex normals of the vertices at slots [begin, end) (3 floats per
  // vertex, mesh order) from the whole mesh's deformed positions.
  void vertex_normals(int begin, int end, std::span<const float> positions, std::span<float> normals) const;
  // Normals are computed for groups of this many consecutive slots: a range that starts or
  // ends inside a group computes the whole group and writes only its own part of it, so callers
  // cutting the sequence into ranges should cut at multiples of this.
  int normal_group_size() const;
  // The vertex at a slot of the sequence. The sequence is made of groups of normal_group_size()
  // consecutive vertices (the last may be shorter, and comes last), so no cache line of the
  // buffers holds vertices of both halves.
  int sequence_vertex(int slot) const;
  // The first slot of the upper half: a multiple of normal_group_size().
  int upper_half_slot() const;

  // All stages on the calling thread. `normals` may be empty (not wanted).
  bool deform(std::span<const Vec3> markers, std::span<float> positions, std::span<float> normals);

  int vertex_count() const;
  DeformationMode mode() const;
  // One part's fit at the solved frame (for tools that ask how a single part would move a
  // point, e.g. eval-deform's worst vertices).
  const PartDeformer& part(int part) const;
  // Heap bytes held by the runtime state (the evaluator's per-vertex data and fans, the parts).
  size_t memory_bytes() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace skinstream
