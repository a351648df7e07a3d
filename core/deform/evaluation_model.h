#pragma once
// The static half of eqs. 8 and 9 in float: everything that turns one frame's part parameters
// (core/deform/part_parameters.h) into the deformed mesh. The daemon builds it from the subject
// (make_evaluation_model) and evaluates its own frames with it; a renderer receives the same
// floats in the subscriber protocol's Model message, so both evaluate the same numbers with the
// same code (core/deform/mesh_evaluator.h). No Eigen here: the C++ client library builds this.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace skinstream {

// A part's local reference frame, its members' box and RBF dilation.
struct EvaluationPart {
  std::array<float, 9> rotation{1, 0, 0, 0, 1, 0, 0, 0, 1};  // R^0: world -> local, row-major
  std::array<float, 3> translation{};                         // d^0: local = R^0 world + d^0
  std::array<float, 3> box_min{}, box_max{};                  // the members' box, local frame
  float sigma = 0.0f;                                         // RBF dilation; 0: no RBF term
  int member_count = 0;
};

struct EvaluationModel {
  std::vector<float> reference_vertices;  // v^0, 3 per vertex, mm, world
  std::vector<std::array<int, 3>> faces;  // for the normals (counter-clockwise from outside)
  std::vector<EvaluationPart> parts;
  std::vector<float> member_reference;  // p^0 of every member, 3 each, part after part, local frame
  std::vector<int> influence_offsets{0};  // CSR over vertices into the two below
  std::vector<int> influence_parts;
  std::vector<float> influence_weights;  // beta; each vertex's sum to 1

  int vertex_count() const { return static_cast<int>(reference_vertices.size() / 3); }
  int part_count() const { return static_cast<int>(parts.size()); }
  int member_count() const { return static_cast<int>(member_reference.size() / 3); }
  int influence_count() const { return static_cast<int>(influence_parts.size()); }
  // The first member of part p in member_reference (and in a frame's weights).
  int first_member(int part) const;

  // Empty when the model is consistent (sizes, indices, finite values, boxes, weights);
  // otherwise what is wrong, in one line. A model from the network must pass this before use.
  std::string validate() const;
};

}  // namespace skinstream
