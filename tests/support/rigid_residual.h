#pragma once
// RMS distance left after the best rigid motion taking points a onto points b: how much of a
// motion is not rigid. Uses the project's Horn fit (tested on its own against an SVD reference).
#include <cmath>
#include <vector>

#include "core/absolute_orientation.h"

namespace skinstream::test {

inline double rigid_residual(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  RigidTransform t;
  fit_rigid(a, b, t);
  double s = 0.0;
  for (size_t i = 0; i < a.size(); ++i) s += (t.apply(a[i]) - b[i]).squaredNorm();
  return std::sqrt(s / a.size());
}

}  // namespace skinstream::test
