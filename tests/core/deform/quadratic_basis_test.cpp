#include "core/deform/quadratic_basis.h"

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace skinstream
