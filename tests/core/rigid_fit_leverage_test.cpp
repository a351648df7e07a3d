#include "core/rigid_fit_leverage.h"

#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "core/absolute_orientation.h"

namespace skinstream {
namespace {

// |J_k|_F^2 / 3 by central differences of the fitted origin (eq. 2's estimate) on target k.
double numerical_leverage(const std::vector<Vec3>& source, int k) {
  constexpr double h = 1e-4;
  double sum = 0.0;
  for (int axis = 0; axis < 3; ++axis) {
    std::vector<Vec3> plus = source, minus = source;
    plus[k](axis) += h;
    minus[k](axis) -= h;
    RigidTransform a, b;
    fit_rigid(source, plus, a);
    fit_rigid(source, minus, b);
    sum += ((a.translation - b.translation) / (2.0 * h)).squaredNorm();
  }
  return sum / 3.0;
}

TEST(RigidFitLeverage, EachPointTakesAnNthSquaredWhenTheMarkerIsAtTheCentroid) {
  const std::vector<Vec3> source = {{50, 0, 0}, {-50, 0, 0}, {0, 50, 0}, {0, -50, 0}, {0, 0, 50}, {0, 0, -50}};
  std::vector<double> leverage(source.size());
  rigid_fit_leverage(source, leverage);
  for (double l : leverage) EXPECT_NEAR(l, 1.0 / 36.0, 1e-9);
}

TEST(RigidFitLeverage, MatchesTheFitsOwnDerivative) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-80.0, 80.0);
  for (int n : {3, 4, 7}) {
    std::vector<Vec3> source(n);
    for (Vec3& p : source) p = Vec3(u(rng) + 60.0, u(rng), u(rng));  // the marker off the centroid
    std::vector<double> leverage(n);
    rigid_fit_leverage(source, leverage);
    for (int k = 0; k < n; ++k) EXPECT_NEAR(leverage[k], numerical_leverage(source, k), 1e-4 * (1.0 + leverage[k])) << n << " points, point " << k;
  }
}

// Members nearly on a line (a finger, a forearm and an upper arm with the elbow straight) leave
// the turn about that line to their small offsets: a marker beside the line moves far more than
// the error of any one member.
TEST(RigidFitLeverage, NearlyCollinearMembersMagnifyErrors) {
  const std::vector<Vec3> spread = {{100, 0, 0}, {-50, 90, 0}, {-50, -90, 0}};
  const std::vector<Vec3> collinear = {{100, 150, 0}, {100, 300, 3}, {100, 450, -3}};
  std::vector<double> a(3), b(3);
  rigid_fit_leverage(spread, a);
  rigid_fit_leverage(collinear, b);
  EXPECT_GT(b[0] + b[1] + b[2], 20.0 * (a[0] + a[1] + a[2]));
  for (int k = 0; k < 3; ++k) EXPECT_TRUE(std::isfinite(b[k]));
}

}  // namespace
}  // namespace skinstream
