#include "core/offline/marker_distance_stats.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace skinstream {

Eigen::MatrixXd MarkerDistanceStats::skin_distance(double k) const {
  Eigen::MatrixXd d = mean + k * stddev;
  for (Eigen::Index i = 0; i < d.rows(); ++i)
    for (Eigen::Index j = 0; j < d.cols(); ++j)
      if (samples(i, j) == 0) d(i, j) = std::numeric_limits<double>::infinity();
  d.diagonal().setZero();
  return d;
}

MarkerDistanceStats compute_marker_distance_stats(const Capture& capture, const std::vector<int>& markers,
                                                  int max_frames) {
  const int n = static_cast<int>(markers.size());
  MarkerDistanceStats s;
  Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(n, n), sum_sq = Eigen::MatrixXd::Zero(n, n);
  s.samples = Eigen::MatrixXi::Zero(n, n);
  const int step = std::max(1, capture.frame_count / std::max(1, max_frames));
  for (int f = 0; f < capture.frame_count; f += step) {
    for (int a = 0; a < n; ++a) {
      const Vec3& pa = capture.at(f, markers[a]);
      if (!is_present(pa)) continue;
      for (int b = a + 1; b < n; ++b) {
        const Vec3& pb = capture.at(f, markers[b]);
        if (!is_present(pb)) continue;
        const double d = (pa - pb).norm();
        sum(a, b) += d;
        sum_sq(a, b) += d * d;
        ++s.samples(a, b);
      }
    }
  }
  s.mean = Eigen::MatrixXd::Zero(n, n);
  s.stddev = Eigen::MatrixXd::Zero(n, n);
  for (int a = 0; a < n; ++a) {
    for (int b = a + 1; b < n; ++b) {
      const int count = s.samples(a, b);
      s.samples(b, a) = count;
      if (count == 0) continue;
      const double m = sum(a, b) / count;
      const double var = std::max(0.0, sum_sq(a, b) / count - m * m);
      s.mean(a, b) = s.mean(b, a) = m;
      s.stddev(a, b) = s.stddev(b, a) = std::sqrt(var);
    }
  }
  return s;
}

std::vector<double> nearest_marker_distances(std::span<const Vec3> positions) {
  std::vector<double> nearest(positions.size(), std::numeric_limits<double>::infinity());
  for (size_t i = 0; i < positions.size(); ++i)
    for (size_t k = i + 1; k < positions.size(); ++k) {
      const double d = (positions[i] - positions[k]).norm();
      nearest[i] = std::min(nearest[i], d);
      nearest[k] = std::min(nearest[k], d);
    }
  return nearest;
}

double median_nearest_marker_distance(std::span<const Vec3> positions) {
  if (positions.size() < 2) throw std::invalid_argument("the nearest-marker distance needs two markers");
  std::vector<double> nearest = nearest_marker_distances(positions);
  std::nth_element(nearest.begin(), nearest.begin() + nearest.size() / 2, nearest.end());
  return nearest[nearest.size() / 2];
}

}  // namespace skinstream
