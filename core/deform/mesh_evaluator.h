#pragma once
// Eqs. 8 and 9 over the whole detailed mesh from one frame's part parameters, and the vertex
// normals: the half of section 5.3's per-frame job that needs no markers. The daemon runs it
// after fitting the parts (MeshDeformer); a renderer that receives the parameters runs the same
// code on the same floats (the C++ client library), so both get the same vertices.
//
// Split in stages so a caller with threads can share the work out by ranges (core/ has no
// threads itself): set_part() for every part, then deform_clusters() over disjoint cluster
// ranges, then blend_vertices() over vertex ranges, then vertex_normals() over vertex ranges;
// each stage reads what the one before wrote. Vertex ranges count in the evaluator's own vertex
// sequence (sequence_vertex): a permutation of the mesh's vertices whose two halves are
// spatially compact, so that threads given one half each mostly read what they wrote
// themselves. The buffers are always in the mesh's own vertex order.
// Buffers are sized at construction; no stage allocates.

#include <memory>
#include <span>

#include "core/deform/evaluation_model.h"
#include "core/deform/part_parameters.h"

namespace skinstream {

class MeshEvaluator {
 public:
  // Throws std::invalid_argument when the model does not validate. Starts in the rest pose
  // (rest_parameters).
  explicit MeshEvaluator(const EvaluationModel& model);
  ~MeshEvaluator();
  MeshEvaluator(const MeshEvaluator&) = delete;
  MeshEvaluator& operator=(const MeshEvaluator&) = delete;

  // One part's fit at this frame: `weights` holds its members' RBF weights, 3 each. Different
  // parts may be set concurrently.
  void set_part(int part, const PartParameters& parameters, std::span<const float> weights);
  // Every part, from a whole frame's parameters (sized for this model: false, keeping the
  // previous frame, when not, or when a value is not finite).
  bool set_parameters(const FrameParameters& parameters);

  // Eq. 8 for the influences (vertex, part) of clusters [begin, end), each weighted by its
  // beta. Influences are grouped in clusters of nearby vertices of one part, evaluated in
  // vector lanes, so that only the RBF centres within the kernel's support are summed.
  void deform_clusters(int begin, int end);
  int cluster_count() const;
  int cluster_part(int cluster) const;
  // Whether the cluster's influences are of vertices in the upper half of the vertex sequence
  // (slots [upper_half_slot(), vertex_count)); otherwise all are in the lower half. The
  // clusters of a part come lower half first.
  bool cluster_in_upper_half(int cluster) const;
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
  bool evaluate(const FrameParameters& parameters, std::span<float> positions, std::span<float> normals);

  int vertex_count() const;
  int part_count() const;
  // Heap bytes held (the per-vertex data, clusters and fans).
  size_t memory_bytes() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

// The parameters of the reference pose: every part at its reference frame, A = [I 0 0], no RBF.
FrameParameters rest_parameters(const EvaluationModel& model);

}  // namespace skinstream
