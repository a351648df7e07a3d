#pragma once
// One frame of the deformation in float (section 5.3): per part the quadratic transformation
// A_t, the rigid transform R_t, d_t and whether the RBF residual applies, and per member its RBF
// weight w. With the EvaluationModel this is all a renderer needs to evaluate the mesh; it is
// what the subscriber protocol's parameter encoding sends (docs/subscriber-protocol.md).

#include <array>
#include <cstdint>
#include <vector>

namespace skinstream {

struct PartParameters {
  std::array<float, 27> quadratic{};  // A_t, 3 x 9 row-major
  std::array<float, 9> rotation{};    // R_t: world -> local, row-major
  std::array<float, 3> translation{};  // d_t: local = R_t world + d_t
  bool rbf = false;                    // the RBF term applies this frame
};

struct FrameParameters {
  std::vector<PartParameters> parts;
  std::vector<float> weights;  // 3 per member (x y z), in the EvaluationModel's member order

  // Sized for a model of this many parts and members (the per-frame path then only overwrites).
  void resize(int part_count, int member_count) {
    parts.assign(static_cast<size_t>(part_count), PartParameters{});
    weights.assign(3 * static_cast<size_t>(member_count), 0.0f);
  }
};

}  // namespace skinstream
