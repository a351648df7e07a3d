#pragma once
// The 9-dimensional quadratic vector q(p) of section 5.3: linear, pure quadratic and mixed
// quadratic terms. There is no constant term: the local part frame is centred, so translation
// is carried by the rigid transform, not by the quadratic transformation A.

#include <Eigen/Core>

#include "core/capture.h"
#include "core/deform/quadratic_terms.h"

namespace skinstream {

using QuadraticVector = Eigen::Matrix<double, 9, 1>;
using QuadraticTransform = Eigen::Matrix<double, 3, 9>;  // A = [A1 A2 A3]

inline QuadraticVector quadratic_basis(const Vec3& p) {
  double terms[9];
  quadratic_terms(p.x(), p.y(), p.z(), terms);
  return Eigen::Map<const QuadraticVector>(terms);
}

// A = [I 0 0]: maps every position to itself.
inline QuadraticTransform identity_quadratic_transform() {
  QuadraticTransform a = QuadraticTransform::Zero();
  a.leftCols<3>().setIdentity();
  return a;
}

}  // namespace skinstream
