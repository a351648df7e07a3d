#include "core/subject_model.h"

#include <cmath>
#include <cstdint>
#include <sstream>

namespace skinstream {

double SubjectModel::neighbour_distance(int i) const {
  const int count = ring_size(i);
  if (count == 0) return 0.0;
  double sum = 0.0;
  for (int k = ring_offsets[i]; k < ring_offsets[i + 1]; ++k) sum += ring_local_reference[k].norm();
  return sum / count;
}

int SubjectModel::marker_index(const std::string& name) const {
  for (int i = 0; i < marker_count(); ++i)
    if (marker_names[i] == name) return i;
  return -1;
}

std::string SubjectModel::validate() const {
  std::ostringstream why;
  const size_t n = marker_names.size();
  if (n == 0) return "no markers";
  if (reference_positions.size() != n) why << "reference pose has " << reference_positions.size() << " markers, expected " << n << "; ";
  if (ring_offsets.size() != n + 1 || ring_offsets.front() != 0 || ring_offsets.back() != static_cast<int>(ring.size()))
    return why.str() + "one-ring offsets inconsistent";
  if (ring_local_reference.size() != ring.size()) why << "local reference positions do not match the one-rings; ";
  if (local_reference_frames.size() != n) why << "local frames count " << local_reference_frames.size() << "; ";
  if (anchor_offsets.size() != n + 1 || anchor_offsets.front() != 0 || anchor_offsets.back() != static_cast<int>(anchors.size()))
    why << "anchor offsets inconsistent; ";
  if (pca.size() != n) why << "PCA models count " << pca.size() << "; ";
  if (!why.str().empty()) return why.str();
  for (size_t i = 0; i < n; ++i) {
    if (!is_present(reference_positions[i])) why << "marker " << marker_names[i] << " has no reference position; ";
    // In 64 bits and judged before it sizes anything: offsets from a file can be any int.
    const int64_t ring_size = int64_t{ring_offsets[i + 1]} - ring_offsets[i];
    if (ring_size < 0 || ring_size > kMaxRing) {
      why << "marker " << marker_names[i] << " ring size " << ring_size << "; ";
      continue;
    }
    const int rs = static_cast<int>(ring_size);
    const MarkerPcaModel& m = pca[i];
    if (m.mean.size() != 3 * rs || m.basis.rows() != 3 * rs || m.basis.cols() != m.variance.size())
      why << "marker " << marker_names[i] << " PCA shape does not match its ring; ";
    else if (m.slot_calibration.size() != rs || !(m.slot_calibration.array() > 0).all() || !(m.rigid_variance > 0))
      why << "marker " << marker_names[i] << " calibration missing or not positive; ";
    else if (!m.mean.allFinite() || !m.basis.allFinite() || !m.variance.allFinite() || !std::isfinite(m.residual_variance) ||
             !(m.residual_variance > 0) || !(m.variance.array() > 0).all())
      why << "marker " << marker_names[i] << " PCA has non-finite values; ";
  }
  if (has_regions()) {
    if (region_pca.size() != n || region_offsets.size() != n + 1 || region_offsets.front() != 0 ||
        region_offsets.back() != static_cast<int>(region.size()))
      return why.str() + "regions inconsistent";
    for (int j : region)
      if (j < 0 || j >= static_cast<int>(n)) return why.str() + "region index out of range";
    for (size_t i = 0; i < n; ++i) {
      const int64_t size = int64_t{region_offsets[i + 1]} - region_offsets[i];
      const MarkerPcaModel& m = region_pca[i];
      if (size < 1 || size > kMaxRing || region[region_offsets[i]] != static_cast<int>(i))
        why << "marker " << marker_names[i] << " region malformed; ";
      else if (m.mean.size() != 3 * size || m.basis.rows() != 3 * size || m.basis.cols() != m.variance.size() ||
               m.slot_calibration.size() != size)
        why << "marker " << marker_names[i] << " region PCA shape does not match its region; ";
      else if (!m.mean.allFinite() || !m.basis.allFinite() || !(m.variance.array() > 0).all() ||
               !(m.residual_variance > 0) || !std::isfinite(m.residual_variance) || !(m.slot_calibration.array() > 0).all())
        why << "marker " << marker_names[i] << " region PCA has non-finite or non-positive values; ";
    }
  }
  for (int j : ring)
    if (j < 0 || j >= static_cast<int>(n)) return why.str() + "one-ring index out of range";
  for (int j : anchors)
    if (j < 0 || j >= static_cast<int>(n)) return why.str() + "anchor index out of range";
  for (const auto& t : triangles)
    for (int v : t)
      if (v < 0 || v >= static_cast<int>(n)) return why.str() + "triangle index out of range";
  return why.str();
}

}  // namespace skinstream
