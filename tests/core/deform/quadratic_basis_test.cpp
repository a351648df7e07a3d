#include "core/deform/quadratic_basis.h"

#include <gtest/gtest.h>

#include "core/deform/rbf_kernel.h"

namespace skinstream {
namespace {

TEST(QuadraticBasis, OrderIsLinearPureMixed) {
  const QuadraticVector q = quadratic_basis(Vec3(2, 3, 5));
  QuadraticVector expected;
  expected << 2, 3, 5, 4, 9, 25, 6, 15, 10;
  EXPECT_EQ(q, expected);
}

// The mesh deformer forms the terms in float lanes through the same template.
TEST(QuadraticBasis, TermsOfAnyTypeInTheBasisOrder) {
  float terms[9];
  quadratic_terms(2.0f, 3.0f, 5.0f, terms);
  const QuadraticVector q = quadratic_basis(Vec3(2, 3, 5));
  for (int k = 0; k < 9; ++k) EXPECT_EQ(terms[k], static_cast<float>(q[k])) << k;
}

TEST(QuadraticBasis, IdentityTransformKeepsPosition) {
  const Vec3 p(-7.5, 12.25, 3.0);
  EXPECT_EQ(identity_quadratic_transform() * quadratic_basis(p), p);
}

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

}  // namespace
}  // namespace skinstream
