#include "core/fitting/scan_body.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/geometry/triangle_bvh.h"

namespace skinstream {

namespace {

Vec3 extent_low(std::span<const Vec3> points) {
  Vec3 low = Vec3::Constant(std::numeric_limits<double>::infinity());
  for (const Vec3& p : points) low = low.cwiseMin(p);
  return low;
}
Vec3 extent_high(std::span<const Vec3> points) {
  Vec3 high = Vec3::Constant(-std::numeric_limits<double>::infinity());
  for (const Vec3& p : points) high = high.cwiseMax(p);
  return high;
}

// The point of a surface nearest to p, as a place on it.
MarkerAttachment nearest_place(const Vec3& p, const std::vector<Vec3>& vertices, const std::vector<Triangle>& triangles,
                               const TriangleBvh& bvh) {
  MarkerAttachment a;
  bvh.closest(p, &a.triangle);
  const Triangle& t = triangles[static_cast<size_t>(a.triangle)];
  closest_point_on_triangle(p, vertices[t[0]], vertices[t[1]], vertices[t[2]], &a.barycentric);
  return a;
}

}  // namespace

ScanBody skin_scan(const Body& template_body, const TemplateSegments& segments, std::span<const Vec3> scan,
                   std::span<const Triangle> scan_triangles, const ScanBodyOptions& options) {
  if (scan.empty() || scan_triangles.empty()) throw std::invalid_argument("the scan has no vertices or no triangles");
  const FitBody body = fit_body_of(template_body, segments);

  // 1. The template fitted to points of the scan, as to one frame of markers on the skin. The scan
  // stands upright facing +Y already: the first guess puts the template's box on the scan's.
  std::vector<Vec3> points;
  const size_t stride = std::max<size_t>(1, scan.size() / static_cast<size_t>(std::max(1, options.points)));
  for (size_t v = 0; v < scan.size(); v += stride) points.push_back(scan[v]);
  const Vec3 scan_low = extent_low(scan), scan_high = extent_high(scan);
  const Vec3 low = extent_low(body.rest), high = extent_high(body.rest);
  Similarity start;
  start.scale = (scan_high.z() - scan_low.z()) / (high.z() - low.z());
  start.rigid.translation = 0.5 * (scan_low + scan_high) - start.scale * 0.5 * (low + high);
  ActorFitOptions fit_options = options.fit;
  fit_options.start = start;
  const int count = static_cast<int>(points.size());
  const std::vector<MarkerPrior> unnamed(static_cast<size_t>(count));
  const ActorFit fit = fit_actor(body, points, 1, count, 0, unnamed, fit_options);

  ScanBody out;
  out.fit_rms_mm = fit.rms_mm;
  // 2. Registered onto the points: each point's fitted place is its landmark.
  std::vector<RegistrationLandmark> landmarks;
  for (int i = 0; i < count; ++i)
    if (fit.attachments[i].triangle >= 0)
      landmarks.push_back({i, body.triangles[fit.attachments[i].triangle][0], fit.attachments[i].triangle, fit.attachments[i].barycentric});
  RegistrationOptions registration = options.registration;
  registration.marker_offset_mm = 0.0;
  RegistrationReport report;
  out.template_on_scan = register_mesh(fit.reference_vertices, body.triangles, points, landmarks, registration, &report);
  out.registered_rms_mm = report.after.rms;

  // 3. The scan inherits the template's segment weights, vertex by vertex, and its joints.
  const TriangleBvh on_scan(out.template_on_scan, body.triangles);
  FitBody& skinned = out.body;
  skinned.rest.assign(scan.begin(), scan.end());
  skinned.triangles.assign(scan_triangles.begin(), scan_triangles.end());
  std::vector<double> distances;
  for (const Vec3& v : scan) {
    Vec3 nearest;
    distances.push_back(on_scan.closest(v, nullptr, &nearest));
    const MarkerAttachment place = nearest_place(v, out.template_on_scan, body.triangles, on_scan);
    attachment_segment_weights(place, body.triangles, body.weights, skinned.weights.weights);
    skinned.weights.offsets.push_back(static_cast<int>(skinned.weights.weights.size()));
  }
  std::sort(distances.begin(), distances.end());
  out.inherited_median_mm = distances[distances.size() / 2];
  out.inherited_max_mm = distances.back();
  skinned.segment_names = body.segment_names;
  skinned.segment_parents = body.segment_parents;
  // Joints where the fit put them (the scan's pose), twist axes turned with their segments.
  std::vector<Eigen::Matrix3d> turn(static_cast<size_t>(body.segment_count()));
  for (int s = 0; s < body.segment_count(); ++s) {
    const int parent = body.segment_parents[s];
    turn[s] = parent < 0 ? fit.poses[0].local[s] : Eigen::Matrix3d(turn[parent] * fit.poses[0].local[s]);
    skinned.rest_pivots.push_back(fit.reference_skeleton.segments[s].pivot);
    skinned.twist_axes.push_back(turn[s] * body.twist_axes[s]);
  }
  return out;
}

std::vector<MarkerPrior> transfer_priors(std::span<const MarkerPrior> template_priors,
                                         std::span<const Triangle> template_triangles, const ScanBody& scan) {
  const TriangleBvh bvh(scan.body.rest, scan.body.triangles);
  auto point_on_template = [&](int triangle, const Vec3& barycentric) {
    const Triangle& t = template_triangles[static_cast<size_t>(triangle)];
    return Vec3(barycentric[0] * scan.template_on_scan[t[0]] + barycentric[1] * scan.template_on_scan[t[1]] +
                barycentric[2] * scan.template_on_scan[t[2]]);
  };
  // Each scan triangle's counterpart: the template triangle nearest to its centre.
  const TriangleBvh on_scan(scan.template_on_scan, std::vector<Triangle>(template_triangles.begin(), template_triangles.end()));
  std::vector<int> counterpart(scan.body.triangles.size());
  for (size_t t = 0; t < counterpart.size(); ++t) {
    const Triangle& tri = scan.body.triangles[t];
    on_scan.closest((scan.body.rest[tri[0]] + scan.body.rest[tri[1]] + scan.body.rest[tri[2]]) / 3.0, &counterpart[t]);
  }
  std::vector<char> allowed(template_triangles.size(), 0);
  std::vector<MarkerPrior> out;
  for (const MarkerPrior& prior : template_priors) {
    MarkerPrior moved;
    if (prior.place.triangle >= 0) {
      moved.place = nearest_place(point_on_template(prior.place.triangle, prior.place.barycentric), scan.body.rest,
                                  scan.body.triangles, bvh);
      moved.place.offset_mm = prior.place.offset_mm;
    }
    for (int t : prior.allowed_triangles) allowed[static_cast<size_t>(t)] = 1;
    for (size_t t = 0; t < counterpart.size(); ++t)
      if (allowed[static_cast<size_t>(counterpart[t])]) moved.allowed_triangles.push_back(static_cast<int>(t));
    for (int t : prior.allowed_triangles) allowed[static_cast<size_t>(t)] = 0;
    if (moved.place.triangle >= 0 && moved.allowed_triangles.empty()) moved.allowed_triangles.push_back(moved.place.triangle);
    out.push_back(std::move(moved));
  }
  return out;
}

}  // namespace skinstream
