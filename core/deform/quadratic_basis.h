#pragma once
// The 9-dimensional quadratic vector q(p) of section 5.3: linear, pure quadratic and mixed
// quadratic terms. There is no constant term: the local part frame is centred, so translation
// is carried by the rigid transform, not by the quadratic transformation A.

#include <Eigen/Core>

#include "core/capture.h"

namespace skinstream {

using QuadraticVector = Eigen::Matrix<double, 9, 1>;
using QuadraticTransform = Eigen::Matrix<double, 3, 9>;  // A = [A1 A2 A3]

// The nine terms in their order, for any arithmetic type: the mesh deformer forms them for a
// vector of lanes at once, and must agree with the offline Q^0 on the order.
template <typename T>
inline void quadratic_terms(const T& x, const T& y, const T& z, T (&q)[9]) {
  q[0] = x, q[1] = y, q[2] = z;
  q[3] = x * x, q[4] = y * y, q[5] = z * z;
  q[6] = x * y, q[7] = y * z, q[8] = z * x;
}

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
