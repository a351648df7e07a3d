#pragma once
// Radial basis function of eq. 7/8: the uniform cubic B-spline with support 2, evaluated at the
// distance already divided by the dilation sigma. phi(0) = 2/3, phi(1) = 1/6, phi(>=2) = 0.

namespace skinstream {

inline double cubic_bspline_kernel(double r) {
  if (r < 0) r = -r;
  if (r >= 2.0) return 0.0;
  const double far = 2.0 - r;
  if (r >= 1.0) return far * far * far / 6.0;
  const double near = 1.0 - r;
  return (far * far * far - 4.0 * near * near * near) / 6.0;
}

}  // namespace skinstream
