#pragma once
// A region's shape (its members after rigid alignment, region_pca_fit.h) as a Gaussian: the
// form in which the offline PCA model and what was learned online (region_online_statistics.h)
// are blended. The offline model's Gaussian is its kept components, mean + basis * c with
// c ~ N(0, diag(variance)); the isotropic residual is kept apart, so that a blend of covariances
// never drops below what the model could not explain.

#include "core/pca_fit.h"
#include "core/subject_model.h"

namespace skinstream {

struct RegionShapeGaussian {
  PcaVector mean;         // 3 * members, in the region's aligned frame
  PcaMatrix covariance;   // 3 * members square: the shape's covariance, residual not included
  double residual_variance = 0.0;  // per coordinate, added to every member (mm^2)
  double calibration = 1.0;        // member 0's predictive variance is multiplied by this

  int members() const { return static_cast<int>(mean.size() / 3); }
};

// The offline model's Gaussian (its kept components and residual, member 0's calibration).
// Allocation-free: the output has fixed capacity.
void region_gaussian_from_pca(const MarkerPcaModel& model, RegionShapeGaussian& out);

}  // namespace skinstream
