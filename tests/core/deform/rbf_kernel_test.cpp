#include "core/deform/rbf_kernel.h"

#include <gtest/gtest.h>

#include <random>

namespace skinstream {
namespace {

TEST(RbfKernel, CubicBSplineValues) {
  EXPECT_DOUBLE_EQ(cubic_bspline_kernel(0.0), 2.0 / 3.0);
  EXPECT_DOUBLE_EQ(cubic_bspline_kernel(1.0), 1.0 / 6.0);
  EXPECT_DOUBLE_EQ(cubic_bspline_kernel(0.5), (1.5 * 1.5 * 1.5 - 4 * 0.125) / 6.0);
  EXPECT_DOUBLE_EQ(cubic_bspline_kernel(1.5), 0.125 / 6.0);
  EXPECT_EQ(cubic_bspline_kernel(2.0), 0.0);
  EXPECT_EQ(cubic_bspline_kernel(3.0), 0.0);
  EXPECT_DOUBLE_EQ(cubic_bspline_kernel(-0.5), cubic_bspline_kernel(0.5));
}

TEST(RbfKernel, ContinuousAtKnots) {
  for (double knot : {1.0, 2.0})
    EXPECT_NEAR(cubic_bspline_kernel(knot - 1e-9), cubic_bspline_kernel(knot + 1e-9), 1e-8);
}

// The matrix is filled without the scalar kernel's branches, in vector lanes; every entry must
// still be phi(|c_i - c_j| / sigma), on all three pieces (r < 1, 1 <= r < 2, r >= 2), and the
// matrix symmetric. Sizes around the vector widths, so partial lanes are covered too.
TEST(RbfKernel, KernelMatrixIsTheScalarKernelOfEveryPair) {
  std::mt19937_64 rng(71);
  std::uniform_real_distribution<double> coordinate(-60.0, 60.0);
  const double sigma = 25.0;  // pairs span r from 0 to about 8
  for (int count : {1, 2, 3, 7, 8, 9, 17, 40, 148}) {
    Eigen::MatrixX3d centres(count, 3);
    for (int i = 0; i < count; ++i)
      for (int a = 0; a < 3; ++a) centres(i, a) = coordinate(rng);
    Eigen::MatrixXd kernel = Eigen::MatrixXd::Constant(count, count, -1.0);
    fill_rbf_kernel(centres, sigma, kernel);
    int pieces[3] = {0, 0, 0};
    for (int i = 0; i < count; ++i)
      for (int j = 0; j < count; ++j) {
        const double r = (centres.row(i) - centres.row(j)).norm() / sigma;
        ++pieces[r < 1.0 ? 0 : r < 2.0 ? 1 : 2];
        EXPECT_NEAR(kernel(i, j), cubic_bspline_kernel(r), 1e-15) << count << ": " << i << ", " << j << " r " << r;
        EXPECT_EQ(kernel(i, j), kernel(j, i));
      }
    if (count == 148) {
      for (int piece : pieces) EXPECT_GT(piece, count) << "every piece of the kernel is exercised";
    }
  }
}

}  // namespace
}  // namespace skinstream
