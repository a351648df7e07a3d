#include "core/fitting/marker_priors.h"

namespace skinstream {

MarkerPriors marker_priors(std::span<const std::string> labels, const Body& body, std::span<const Triangle> triangles,
                           std::span<const MarkerSet> sets) {
  MarkerPriors out;
  out.priors.resize(labels.size());
  if (sets.empty()) return out;
  const MarkerSetMatch match = match_marker_set(sets, labels);
  out.description = describe_match(sets, labels, match);
  if (match.set < 0) return out;
  const MarkerSet& set = sets[static_cast<size_t>(match.set)];
  out.set_name = set.name;
  out.named = match.matched;
  const std::vector<Triangle> surface(triangles.begin(), triangles.end());
  const TriangleBvh bvh(body.rest, surface);
  for (size_t i = 0; i < labels.size(); ++i) {
    if (match.placement[i] < 0) continue;
    const MarkerPlacement& placement = set.markers[static_cast<size_t>(match.placement[i])];
    MarkerPrior& prior = out.priors[i];
    if (placement.is_region()) {
      const std::vector<char> region = region_triangles(body, triangles, placement);
      for (size_t t = 0; t < region.size(); ++t)
        if (region[t]) prior.allowed_triangles.push_back(static_cast<int>(t));
      continue;
    }
    const SurfacePoint site = place_marker(body, triangles, bvh, placement);
    prior.place.triangle = site.triangle;
    prior.place.barycentric = site.barycentric;
    // The triangles within the set's radius of the site (by a corner), so the fit can slide it.
    for (size_t t = 0; t < triangles.size(); ++t)
      for (int v : triangles[t])
        if ((body.rest[static_cast<size_t>(v)] - site.position).norm() <= placement.radius_mm) {
          prior.allowed_triangles.push_back(static_cast<int>(t));
          break;
        }
    if (prior.allowed_triangles.empty()) prior.allowed_triangles.push_back(site.triangle);
  }
  return out;
}

}  // namespace skinstream
