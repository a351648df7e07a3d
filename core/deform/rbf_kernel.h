#pragma once
// Radial basis function of eq. 7/8: the uniform cubic B-spline with support 2, evaluated at the
// distance already divided by the dilation sigma. phi(0) = 2/3, phi(1) = 1/6, phi(>=2) = 0.

#include <Eigen/Core>

namespace skinstream {

inline double cubic_bspline_kernel(double r) {
  if (r < 0) r = -r;
  if (r >= 2.0) return 0.0;
  const double far = 2.0 - r;
  if (r >= 1.0) return far * far * far / 6.0;
  const double near = 1.0 - r;
  return (far * far * far - 4.0 * near * near * near) / 6.0;
}

// Eq. 7's kernel matrix, phi(|c_i - c_j| / sigma), into `kernel`: Y x Y, sized by the caller,
// so the per-frame solve allocates nothing.
inline void fill_rbf_kernel(const Eigen::Matrix3Xd& centres, double dilation, Eigen::MatrixXd& kernel) {
  const double inverse_sigma = 1.0 / dilation;
  const int count = static_cast<int>(centres.cols());
  for (int j = 0; j < count; ++j) {
    kernel(j, j) = cubic_bspline_kernel(0.0);
    for (int i = j + 1; i < count; ++i) {
      const double value = cubic_bspline_kernel((centres.col(i) - centres.col(j)).norm() * inverse_sigma);
      kernel(i, j) = value;
      kernel(j, i) = value;
    }
  }
}

}  // namespace skinstream
