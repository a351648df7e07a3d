#include "core/region_shape_gaussian.h"

namespace skinstream {

void region_gaussian_from_pca(const MarkerPcaModel& model, RegionShapeGaussian& out) {
  const int dims = static_cast<int>(model.mean.size()), components = static_cast<int>(model.variance.size());
  out.mean = model.mean;
  out.covariance.setZero(dims, dims);
  for (int c = 0; c < components; ++c)
    for (int col = 0; col < dims; ++col) {
      const double scaled = model.variance(c) * model.basis(col, c);
      for (int row = 0; row < dims; ++row) out.covariance(row, col) += model.basis(row, c) * scaled;
    }
  out.residual_variance = model.residual_variance;
  out.calibration = model.slot_calibration.size() > 0 ? model.slot_calibration(0) : 1.0;
}

}  // namespace skinstream
