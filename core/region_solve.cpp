#include "core/region_solve.h"

#include <Eigen/Cholesky>
#include <algorithm>

namespace skinstream {

uint32_t region_observed_mask(std::span<const char> observed) {
  uint32_t mask = 0;
  for (size_t k = 1; k < observed.size(); ++k)
    if (observed[k]) mask |= 1u << k;
  return mask;
}

bool prepare_region_solve(const RegionShapeGaussian& shape, uint32_t mask, long shape_version, RegionSolve& out) {
  out.observed_mask = 0;
  const int size = shape.members();
  out.observed = out.hidden = 0;
  out.hidden_slots[out.hidden++] = 0;
  for (int k = 1; k < size; ++k) {
    if (mask & (1u << k)) out.observed_slots[out.observed++] = k;
    else out.hidden_slots[out.hidden++] = k;
  }
  const int o = out.observed, h = out.hidden;
  if (o < 3) return false;

  PcaMatrix& lower = out.lower;
  lower.resize(3 * o, 3 * o);
  for (int a = 0; a < o; ++a)
    for (int b = 0; b < o; ++b)
      lower.block<3, 3>(3 * a, 3 * b) = shape.covariance.block<3, 3>(3 * out.observed_slots[a], 3 * out.observed_slots[b]);
  lower.diagonal().array() += shape.residual_variance;
  const Eigen::LLT<Eigen::Ref<PcaMatrix>> llt(lower);  // in place: lower now holds L below its diagonal
  if (llt.info() != Eigen::Success) return false;

  // gain = (L L^T)^-1 C_OH, and member 0's variance from |L^-1 C_O0|^2.
  PcaMatrix& gain = out.gain;
  gain.resize(3 * o, 3 * h);
  for (int a = 0; a < o; ++a)
    for (int b = 0; b < h; ++b)
      gain.block<3, 3>(3 * a, 3 * b) = shape.covariance.block<3, 3>(3 * out.observed_slots[a], 3 * out.hidden_slots[b]);
  lower.triangularView<Eigen::Lower>().solveInPlace(gain);
  const double explained = gain.leftCols<3>().squaredNorm();
  lower.triangularView<Eigen::Lower>().transpose().solveInPlace(gain);
  out.variance = std::max(0.0, shape.covariance.topLeftCorner<3, 3>().trace() - explained) / 3.0 + shape.residual_variance;
  out.mean = shape.mean;
  out.calibration = shape.calibration;
  out.residual_variance = shape.residual_variance;
  out.shape_version = shape_version;
  out.observed_mask = mask;
  return true;
}

}  // namespace skinstream
