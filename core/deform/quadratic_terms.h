#pragma once
// The nine terms of the quadratic vector q(p) of section 5.3 (linear, pure quadratic, mixed), for
// any arithmetic type, without Eigen: the mesh evaluator forms them for a vector of lanes at once
// and for the RBF centres, and must agree with the offline Q^0 (quadratic_basis.h) on the order.

namespace skinstream {

template <typename T>
inline void quadratic_terms(const T& x, const T& y, const T& z, T (&q)[9]) {
  q[0] = x, q[1] = y, q[2] = z;
  q[3] = x * x, q[4] = y * y, q[5] = z * z;
  q[6] = x * y, q[7] = y * z, q[8] = z * x;
}

}  // namespace skinstream
