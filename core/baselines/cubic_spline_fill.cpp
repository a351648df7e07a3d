#include "core/baselines/cubic_spline_fill.h"

#include <Eigen/Dense>
#include <algorithm>
#include <stdexcept>

#include "core/baselines/channel_runs.h"

namespace skinstream {

namespace {

// Second derivatives at the knots (one column per coordinate) of the interpolating spline.
Eigen::MatrixX3d knot_second_derivatives(const Eigen::VectorXd& x, const Eigen::MatrixX3d& y, SplineEnd end) {
  const Eigen::Index n = x.size();
  Eigen::MatrixX3d second = Eigen::MatrixX3d::Zero(n, 3);
  if (n < 3) return second;  // two knots: the straight line

  Eigen::MatrixXd system = Eigen::MatrixXd::Zero(n, n);
  Eigen::MatrixX3d rhs = Eigen::MatrixX3d::Zero(n, 3);
  for (Eigen::Index i = 1; i + 1 < n; ++i) {  // continuity of the first derivative at interior knots
    const double h0 = x(i) - x(i - 1), h1 = x(i + 1) - x(i);
    system(i, i - 1) = h0;
    system(i, i) = 2.0 * (h0 + h1);
    system(i, i + 1) = h1;
    rhs.row(i) = 6.0 * ((y.row(i + 1) - y.row(i)) / h1 - (y.row(i) - y.row(i - 1)) / h0);
  }
  if (end == SplineEnd::natural) {
    system(0, 0) = 1.0;
    system(n - 1, n - 1) = 1.0;
  } else if (n == 3) {  // not-a-knot on three knots is the parabola: constant second derivative
    system(0, 0) = 1.0, system(0, 1) = -1.0;
    system(2, 1) = 1.0, system(2, 2) = -1.0;
  } else {  // third derivative continuous at knots 1 and n-2
    const double h0 = x(1) - x(0), h1 = x(2) - x(1);
    system(0, 0) = h1, system(0, 1) = -(h0 + h1), system(0, 2) = h0;
    const double g0 = x(n - 2) - x(n - 3), g1 = x(n - 1) - x(n - 2);
    system(n - 1, n - 3) = g1, system(n - 1, n - 2) = -(g0 + g1), system(n - 1, n - 1) = g0;
  }
  // At most 2 * window knots: a dense solve is simpler than a banded one and just as cheap.
  second = system.partialPivLu().solve(rhs);
  return second;
}

Vec3 evaluate(const Eigen::VectorXd& x, const Eigen::MatrixX3d& y, const Eigen::MatrixX3d& second,
              double at) {
  Eigen::Index i = 0;
  while (i + 2 < x.size() && at > x(i + 1)) ++i;
  const double h = x(i + 1) - x(i);
  const double a = (x(i + 1) - at) / h, b = (at - x(i)) / h;
  const Eigen::RowVector3d value =
      a * y.row(i) + b * y.row(i + 1) +
      ((a * a * a - a) * second.row(i) + (b * b * b - b) * second.row(i + 1)) * (h * h / 6.0);
  return value.transpose();
}

}  // namespace

Capture fill_cubic_spline(const Capture& capture, const CubicSplineOptions& options) {
  require_consistent(capture, "fill_cubic_spline");
  if (options.window < 1) throw std::invalid_argument("fill_cubic_spline: window must be at least 1");
  Capture filled = capture;
  for (int point : capture.labelled_points()) {
    const std::vector<int> present = present_frames(capture, point);
    hold_ends(filled, point, present);
    for (size_t k = 0; k + 1 < present.size(); ++k) {
      if (present[k + 1] - present[k] < 2) continue;
      const size_t first = k + 1 >= static_cast<size_t>(options.window) ? k + 1 - options.window : 0;
      const size_t last = std::min(present.size() - 1, k + options.window);  // inclusive
      const Eigen::Index knots = static_cast<Eigen::Index>(last - first + 1);
      Eigen::VectorXd x(knots);
      Eigen::MatrixX3d y(knots, 3);
      for (Eigen::Index j = 0; j < knots; ++j) {
        x(j) = present[first + j];
        y.row(j) = capture.at(present[first + j], point).transpose();
      }
      const Eigen::MatrixX3d second = knot_second_derivatives(x, y, options.end);
      for (int f = present[k] + 1; f < present[k + 1]; ++f) filled.at(f, point) = evaluate(x, y, second, f);
    }
  }
  return filled;
}

}  // namespace skinstream
