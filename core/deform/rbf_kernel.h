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
// so the per-frame solve allocates nothing. The centres come one per row, so that each
// coordinate lies contiguous and a column of distances is computed in vector lanes; the
// kernel is written as ((2 - r)+^3 - 4 (1 - r)+^3) / 6, cubic_bspline_kernel's function without
// its branches, which no predictor could learn. Branchy and strided, this was the costliest
// step of fitting the 148-member trunk part after the factorisation.
inline void fill_rbf_kernel(const Eigen::MatrixX3d& centres, double dilation, Eigen::MatrixXd& kernel) {
  const double inverse_sigma = 1.0 / dilation;
  const Eigen::Index count = centres.rows();
  for (Eigen::Index j = 0; j < count; ++j) {
    const Eigen::Index below = count - j - 1;
    kernel(j, j) = cubic_bspline_kernel(0.0);
    if (below == 0) continue;
    auto column = kernel.col(j).tail(below).array();  // r first, then phi(r) in place
    column = ((centres.col(0).tail(below).array() - centres(j, 0)).square() +
              (centres.col(1).tail(below).array() - centres(j, 1)).square() +
              (centres.col(2).tail(below).array() - centres(j, 2)).square())
                 .sqrt() *
             inverse_sigma;
    column = ((2.0 - column).max(0.0).cube() - 4.0 * (1.0 - column).max(0.0).cube()) * (1.0 / 6.0);
    kernel.row(j).tail(below) = kernel.col(j).tail(below).transpose();
  }
}

}  // namespace skinstream
