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

// Where the template's arms start when fitted to a scan, beside the rest pose's A: raised
// sideways to the elevations the scan's frame measured. (Forward and overhead starts as well let
// the fit follow a scan's arms held forward, but its subject was then refused all the same, as
// crumpled in the reference pose, for 3.5 s more a build.)
std::vector<std::array<Vec3, 2>> scan_arm_starts(const std::array<double, 2>& elevation_deg) {
  std::array<Vec3, 2> raised;
  for (int side = 0; side < 2; ++side) {
    const double a = elevation_deg[static_cast<size_t>(side)] * M_PI / 180.0;  // NaN stays NaN
    raised[static_cast<size_t>(side)] = Vec3((side == 0 ? -1.0 : 1.0) * std::sin(a), 0.0, -std::cos(a));
  }
  if (!raised[0].allFinite() && !raised[1].allFinite()) return {};
  return {raised};
}

// An offset at a posed vertex turned back into the rest pose: by the inverse of the vertex's blend
// of the segments' rotations, or its heaviest segment's rotation alone when the blend is near
// singular (rotations far apart average to a matrix that squashes space).
Vec3 offset_at_rest(const Vec3& posed_offset, std::span<const SegmentWeight> weights,
                    std::span<const RigidTransform> motions, bool* by_one_segment) {
  *by_one_segment = false;
  if (weights.empty()) return posed_offset;  // a vertex no segment holds stays as it is
  Eigen::Matrix3d blend = Eigen::Matrix3d::Zero();
  const SegmentWeight* heaviest = &weights.front();
  for (const SegmentWeight& w : weights) {
    blend += w.weight * motions[static_cast<size_t>(w.segment)].rotation;
    if (w.weight > heaviest->weight) heaviest = &w;
  }
  // Rotations up to about 110 degrees apart blend to a determinant above 0.2.
  *by_one_segment = !(blend.determinant() > 0.2);
  if (*by_one_segment)
    return motions[static_cast<size_t>(heaviest->segment)].rotation.transpose() * posed_offset;
  return blend.inverse() * posed_offset;
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
  fit_options.arm_starts = scan_arm_starts(options.arm_elevation_deg);
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

  // 3. The scan inherits the template's segment weights, vertex by vertex.
  const TriangleBvh on_scan(out.template_on_scan, body.triangles);
  FitBody& skinned = out.body;
  out.as_given.assign(scan.begin(), scan.end());
  skinned.triangles.assign(scan_triangles.begin(), scan_triangles.end());
  std::vector<double> distances;
  std::vector<MarkerAttachment> places;
  for (const Vec3& v : scan) {
    places.push_back(nearest_place(v, out.template_on_scan, body.triangles, on_scan));
    distances.push_back((v - skin_point(places.back(), out.template_on_scan, body.triangles)).norm());
    attachment_segment_weights(places.back(), body.triangles, body.weights, skinned.weights.weights);
    skinned.weights.offsets.push_back(static_cast<int>(skinned.weights.weights.size()));
  }
  std::sort(distances.begin(), distances.end());
  out.inherited_median_mm = distances[distances.size() / 2];
  out.inherited_max_mm = distances.back();
  skinned.segment_names = body.segment_names;
  skinned.segment_parents = body.segment_parents;

  // 4. Unposed into the fitted template's rest pose, with its joints there. Only the offset from
  // the fitted template (its miss and the scan's own shape: millimetres to centimetres) goes
  // through the inverted blend, so where the blend turns fast (an armpit) no vertex is thrown far;
  // inverting each vertex's whole position tore a wrist seam to 18 times its length.
  skinned.rest.reserve(scan.size());
  for (size_t v = 0; v < scan.size(); ++v) {
    const Vec3 at_rest = skin_point(places[v], fit.rest_vertices, body.triangles);
    const Vec3 posed = skin_point(places[v], fit.reference_vertices, body.triangles);
    const std::span<const SegmentWeight> weights(
        skinned.weights.weights.data() + skinned.weights.offsets[v],
        skinned.weights.weights.data() + skinned.weights.offsets[v + 1]);
    bool by_one_segment = false;
    skinned.rest.push_back(at_rest +
                           offset_at_rest(scan[v] - posed, weights, fit.reference_motions, &by_one_segment));
    out.unposed_by_one_segment += by_one_segment ? 1 : 0;
  }
  skinned.rest_pivots = fit.rest_pivots;
  skinned.twist_axes = body.twist_axes;
  return out;
}

std::vector<MarkerPrior> transfer_priors(std::span<const MarkerPrior> template_priors,
                                         std::span<const Triangle> template_triangles, const ScanBody& scan) {
  // Nearest points are sought in the scan's own pose, where the registered template lies; a place
  // (triangle, barycentric) is the same on the unposed scan.
  const TriangleBvh bvh(scan.as_given, scan.body.triangles);
  // Each scan triangle's counterpart: the template triangle nearest to its centre.
  const TriangleBvh on_scan(scan.template_on_scan, std::vector<Triangle>(template_triangles.begin(), template_triangles.end()));
  std::vector<int> counterpart(scan.body.triangles.size());
  for (size_t t = 0; t < counterpart.size(); ++t) {
    const Triangle& tri = scan.body.triangles[t];
    on_scan.closest((scan.as_given[tri[0]] + scan.as_given[tri[1]] + scan.as_given[tri[2]]) / 3.0,
                    &counterpart[t]);
  }
  std::vector<char> allowed(template_triangles.size(), 0);
  std::vector<MarkerPrior> out;
  for (const MarkerPrior& prior : template_priors) {
    MarkerPrior moved;
    if (prior.place.triangle >= 0) {
      moved.place = nearest_place(skin_point(prior.place, scan.template_on_scan, template_triangles),
                                  scan.as_given, scan.body.triangles, bvh);
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
