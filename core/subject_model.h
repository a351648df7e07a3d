#pragma once
// The per-subject model of section 4, built offline once and read-only at runtime:
// labelled markers, their reference pose, the marker surface with one-rings, the local
// reference frames (eq. 1) and one PCA model per marker over its one-ring (eq. 4-5).

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "core/capture.h"

namespace skinstream {

// PCA of a marker's one-ring expressed in the marker's local frame (eq. 4-5): a vector of
// 3 * ring_size values, z = mean + basis * c, with c ~ N(0, diag(variance)).
struct MarkerPcaModel {
  Eigen::VectorXd mean;        // 3 * ring_size
  Eigen::MatrixXd basis;       // 3 * ring_size x components, orthonormal columns
  Eigen::VectorXd variance;    // components, eigenvalues (mm^2), descending
  double residual_variance = 0.0;  // per dimension, what the kept components leave out (mm^2)
  int training_frames = 0;

  // Calibration on the training take, so that estimates can be weighed against each other:
  // per ring member, the mean squared error of reconstructing it from the rest of the ring
  // divided by the predictive variance the model claimed (1 = honest, > 1 = optimistic) ...
  Eigen::VectorXd slot_calibration;  // ring_size
  // ... and the mean squared error per coordinate of the marker's own rigid estimate (eq. 2).
  double rigid_variance = 0.0;  // mm^2
};

struct FillParameters {
  double alpha1 = 0.5;  // eq. 3: start matching an unlabelled point within alpha1 * neighbour distance
  double alpha2 = 0.6;  // keep a match while within alpha2 * neighbour distance
};

struct SubjectModel {
  // Neighbourhoods are capped so the runtime can use fixed-size scratch buffers.
  static constexpr int kMaxRing = 12;

  std::vector<std::string> marker_names;    // index = marker id
  std::vector<Vec3> reference_positions;    // x_i^0, mm
  std::vector<std::array<int, 3>> triangles;  // the marker surface

  // One-ring of each marker (CSR): ring[ring_offsets[i] .. ring_offsets[i+1]).
  std::vector<int> ring_offsets;
  std::vector<int> ring;
  std::vector<Vec3> ring_local_reference;           // x^_{i,k}^0 of eq. 1, parallel to ring
  std::vector<Eigen::Matrix3d> local_reference_frames;  // R_i^0 = [t b n]^T

  // Markers whose distance to marker i varies least over the training take (CSR): the
  // "nearest rigid part" a marker is held to when nothing better is available.
  std::vector<int> anchor_offsets;
  std::vector<int> anchors;

  std::vector<MarkerPcaModel> pca;  // one per marker

  // Each marker's region (CSR, the marker first, then its nearest by skin distance) and the
  // region's PCA, in the region's aligned frame (region_pca_fit.h). Empty: no regional models
  // (a subject file before version 5).
  std::vector<int> region_offsets;
  std::vector<int> region;
  std::vector<MarkerPcaModel> region_pca;
  FillParameters parameters;

  int marker_count() const { return static_cast<int>(marker_names.size()); }
  int ring_size(int i) const { return ring_offsets[i + 1] - ring_offsets[i]; }
  bool has_regions() const { return !region_pca.empty(); }
  // Average distance from marker i to its one-ring in the reference pose (eq. 3 denominator).
  double neighbour_distance(int i) const;
  int marker_index(const std::string& name) const;  // -1 when absent

  // Empty when consistent; otherwise what is wrong (sizes, indices, non-finite values).
  std::string validate() const;
};

}  // namespace skinstream
