#include "core/deform/body_plausibility.h"

#include <algorithm>
#include <cstdio>
#include <limits>
#include <vector>

#include "core/deform/surface_strain.h"

namespace skinstream {

std::string implausible_body(const SubjectModel& subject, const DeformationModel& model, const BodyPlausibilityLimits& limits) {
  char line[200];
  if (!model.rest_vertices.empty()) {
    const EdgeStrain strain = measure_edge_strain(model.rest_vertices, model.reference_vertices, model.faces, limits.max_strain);
    if (strain.strained_fraction > limits.max_strained_fraction) {
      std::snprintf(line, sizeof line, "the body is crumpled: %.2g%% of its edges strained beyond %.3gx against its rest shape (limit %.2g%%)",
                    100.0 * strain.strained_fraction, limits.max_strain, 100.0 * limits.max_strained_fraction);
      return line;
    }
    if (strain.longest_stretched_edge > limits.max_edge_stretch) {
      std::snprintf(line, sizeof line, "the body is torn: an edge stretched to %.3g typical edges (limit %.3g)",
                    strain.longest_stretched_edge, limits.max_edge_stretch);
      return line;
    }
    const int flipped = count_flipped_triangles(model.rest_vertices, model.reference_vertices, model.faces);
    if (flipped > limits.max_flipped_fraction * model.face_count()) {
      std::snprintf(line, sizeof line, "the body is folded: %d of %d triangles turned over (limit %.2g%%)", flipped,
                    model.face_count(), 100.0 * limits.max_flipped_fraction);
      return line;
    }
  }
  std::vector<double> nearest;
  for (const Vec3& m : subject.reference_positions) {
    double best = std::numeric_limits<double>::infinity();
    for (const Vec3& v : model.reference_vertices) best = std::min(best, (v - m).squaredNorm());
    nearest.push_back(std::sqrt(best));
  }
  std::nth_element(nearest.begin(), nearest.begin() + static_cast<long>(nearest.size() / 2), nearest.end());
  const double median = nearest[nearest.size() / 2];
  if (median > limits.max_median_marker_skin_mm) {
    std::snprintf(line, sizeof line, "the markers are not on the body: their median distance to its skin is %.0f mm (limit %.0f mm)",
                  median, limits.max_median_marker_skin_mm);
    return line;
  }
  return {};
}

}  // namespace skinstream
