#include "core/fitting/initial_alignment.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/geometry/triangle_bvh.h"

namespace skinstream {

namespace {

// Scale as the ratio of RMS radii about the centroids, then Horn on the scaled points.
Similarity fit_similarity(std::span<const Vec3> from, std::span<const Vec3> to) {
  Vec3 a = Vec3::Zero(), b = Vec3::Zero();
  for (size_t k = 0; k < from.size(); ++k) {
    a += from[k];
    b += to[k];
  }
  a /= static_cast<double>(from.size());
  b /= static_cast<double>(to.size());
  double ra = 0.0, rb = 0.0;
  for (size_t k = 0; k < from.size(); ++k) {
    ra += (from[k] - a).squaredNorm();
    rb += (to[k] - b).squaredNorm();
  }
  Similarity s;
  s.scale = ra > 0.0 ? std::sqrt(rb / ra) : 1.0;
  std::vector<Vec3> scaled(from.begin(), from.end());
  for (Vec3& p : scaled) p *= s.scale;
  fit_rigid(scaled, to, s.rigid);
  return s;
}


}  // namespace

Similarity align_named(std::span<const Vec3> template_points, std::span<const Vec3> measured) {
  if (template_points.size() != measured.size()) throw std::invalid_argument("align_named: point counts differ");
  std::vector<Vec3> from, to;
  for (size_t k = 0; k < measured.size(); ++k)
    if (is_present(measured[k]) && template_points[k].allFinite()) {
      from.push_back(template_points[k]);
      to.push_back(measured[k]);
    }
  if (from.size() < 3)
    throw std::invalid_argument("only " + std::to_string(from.size()) + " named markers are present in the frame (3 needed)");
  return fit_similarity(from, to);
}

std::vector<Vec3> capture_up(std::span<const Vec3> frames, int frame_count, int marker_count) {
  if (frame_count < 30) return {};
  const Vec3 axes[6] = {Vec3::UnitX(), -Vec3::UnitX(), Vec3::UnitY(), -Vec3::UnitY(), Vec3::UnitZ(), -Vec3::UnitZ()};
  double spread[6];
  const int step = std::max(1, frame_count / 400);
  for (int a = 0; a < 6; ++a) {
    std::vector<double> lowest;
    for (int f = 0; f < frame_count; f += step) {
      double low = std::numeric_limits<double>::infinity();
      for (int i = 0; i < marker_count; ++i) {
        const Vec3& m = frames[static_cast<size_t>(f) * marker_count + i];
        if (is_present(m)) low = std::min(low, m.dot(axes[a]));
      }
      if (std::isfinite(low)) lowest.push_back(low);
    }
    if (lowest.size() < 10) return {};
    std::sort(lowest.begin(), lowest.end());
    spread[a] = lowest[lowest.size() * 9 / 10] - lowest[lowest.size() / 10];  // the middle 80%
  }
  const int best = static_cast<int>(std::min_element(spread, spread + 6) - spread);
  for (int a = 0; a < 6; ++a)
    if (a != best && spread[a] < 2.0 * spread[best]) return {};  // nothing clearly level
  return {axes[best]};
}

std::vector<BlindAlignment> align_blind(std::span<const Vec3> rest_vertices, std::span<const Triangle> triangles,
                                        std::span<const Vec3> markers, std::span<const Vec3> ups) {
  std::vector<Vec3> seen;
  for (const Vec3& m : markers)
    if (is_present(m)) seen.push_back(m);
  if (seen.size() < 4) throw std::invalid_argument("only " + std::to_string(seen.size()) + " markers are present in the frame (4 needed)");
  const std::vector<Vec3> rest(rest_vertices.begin(), rest_vertices.end());
  const TriangleBvh bvh(rest, std::vector<Triangle>(triangles.begin(), triangles.end()));
  Vec3 low = rest.front(), high = rest.front(), centre = Vec3::Zero();
  for (const Vec3& v : rest) {
    low = low.cwiseMin(v);
    high = high.cwiseMax(v);
  }
  centre = 0.5 * (low + high);
  const double template_height = high.z() - low.z();
  Vec3 marker_centre = Vec3::Zero();
  for (const Vec3& m : seen) marker_centre += m;
  marker_centre /= static_cast<double>(seen.size());

  std::vector<BlindAlignment> out;
  std::vector<Vec3> axes(ups.begin(), ups.end());
  if (axes.empty()) axes = {Vec3::UnitX(), -Vec3::UnitX(), Vec3::UnitY(), -Vec3::UnitY(), Vec3::UnitZ(), -Vec3::UnitZ()};
  std::vector<Vec3> inverse(seen.size()), closest(seen.size());
  std::vector<double> distance(seen.size());
  for (const Vec3& up : axes) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const Vec3& m : seen) {
      lo = std::min(lo, m.dot(up));
      hi = std::max(hi, m.dot(up));
    }
    // Markers sit on the skin, so their span is a little short of the body's height.
    const double scale = std::clamp((hi - lo) / (0.92 * template_height), 0.3, 3.0);
    const Eigen::Matrix3d tilt = Eigen::Quaterniond::FromTwoVectors(Vec3::UnitZ(), up).toRotationMatrix();
    for (int heading = 0; heading < 12; ++heading) {
      Similarity s;
      s.scale = scale;
      s.rigid.rotation = tilt * Eigen::AngleAxisd(heading * M_PI / 6.0, Vec3::UnitZ()).toRotationMatrix();
      s.rigid.translation = marker_centre - s.rigid.rotation * (scale * centre);
      // Iterated closest points, trimmed to the nearer 80% (a marker on an arm the template
      // holds elsewhere must not drag the whole body).
      double score = 0.0;
      for (int round = 0; round < 12; ++round) {
        for (size_t k = 0; k < seen.size(); ++k) {
          inverse[k] = s.rigid.apply_inverse(seen[k]) / s.scale;
          Vec3 point;
          distance[k] = s.scale * bvh.closest(inverse[k], nullptr, &point);
          closest[k] = point;
        }
        std::vector<double> sorted = distance;
        std::sort(sorted.begin(), sorted.end());
        score = sorted[sorted.size() / 2];
        const double keep = sorted[std::min(sorted.size() - 1, sorted.size() * 8 / 10)];
        std::vector<Vec3> from, to;
        for (size_t k = 0; k < seen.size(); ++k)
          if (distance[k] <= keep) {
            from.push_back(closest[k]);
            to.push_back(seen[k]);
          }
        if (from.size() < 3) break;
        RigidTransform rigid;
        std::vector<Vec3> scaled = from;
        for (Vec3& p : scaled) p *= s.scale;
        fit_rigid(scaled, to, rigid);
        s.rigid = rigid;
      }
      out.push_back({s, score});
    }
  }
  std::sort(out.begin(), out.end(), [](const BlindAlignment& a, const BlindAlignment& b) {
    return a.median_distance_mm < b.median_distance_mm;
  });
  return out;
}

}  // namespace skinstream
