#include "core/single_gap_reconstruction.h"

#include <Eigen/Cholesky>

namespace skinstream {

// For every ring member of every model: c = A^-1 B_O^T (z_O - mean_O), the reconstruction
// mean_s + B_s c.
SingleGapReconstruction::SingleGapReconstruction(const SubjectModel& model) : model_(model) {
  offset_.assign(model.ring.size(), 0);
  variance_.assign(model.ring.size(), 0.0);
  for (int j = 0; j < model.marker_count(); ++j) {
    const MarkerPcaModel& m = model.pca[j];
    const int d = model.ring_size(j), components = static_cast<int>(m.variance.size());
    for (int s = 0; s < d; ++s) {
      const int at = model.ring_offsets[j] + s;
      offset_[at] = static_cast<int>(map_.size());
      Eigen::MatrixXd observed(3 * (d - 1), components);
      for (int k = 0, o = 0; k < d; ++k)
        if (k != s) observed.middleRows<3>(3 * o++) = m.basis.middleRows<3>(3 * k);
      Eigen::MatrixXd normal = observed.transpose() * observed;
      for (int c = 0; c < components; ++c) normal(c, c) += m.residual_variance / m.variance(c);
      const Eigen::LLT<Eigen::MatrixXd> llt(normal);
      const Eigen::MatrixXd map = llt.solve(observed.transpose());
      for (int c = 0; c < components; ++c)
        for (int col = 0; col < map.cols(); ++col) map_.push_back(map(c, col));
      const Eigen::MatrixXd rows = m.basis.middleRows<3>(3 * s);
      const double spread = components ? (rows * llt.solve(rows.transpose())).trace() / 3.0 : 0.0;
      variance_[at] = m.residual_variance * (1.0 + spread) * m.slot_calibration(s);
    }
  }
  deviation_.resize(kMaxRingDims);
}

double SingleGapReconstruction::reconstruct(int j, int missing_slot, std::span<const Vec3> local,
                                            std::span<const int> slots, Vec3& out_local) {
  const MarkerPcaModel& m = model_.pca[j];
  const int at = model_.ring_offsets[j] + missing_slot;
  const double* map = map_.data() + offset_[at];  // empty when the model has no components
  const int count = static_cast<int>(local.size());
  const int columns = 3 * count, components = static_cast<int>(m.variance.size());
  for (int o = 0; o < count; ++o) deviation_.segment<3>(3 * o) = local[o] - m.mean.segment<3>(3 * slots[o]);
  coefficients_.resize(components);
  for (int c = 0; c < components; ++c) {
    double sum = 0.0;
    for (int col = 0; col < columns; ++col) sum += map[c * columns + col] * deviation_(col);
    coefficients_(c) = sum;
  }
  double miss = 0.0;
  for (int o = 0; o < count; ++o)
    miss +=
        (deviation_.segment<3>(3 * o) - m.basis.middleRows<3>(3 * slots[o]) * coefficients_).squaredNorm();
  out_local = m.mean.segment<3>(3 * missing_slot) + m.basis.middleRows<3>(3 * missing_slot) * coefficients_;
  return miss;
}

}  // namespace skinstream
