#include "core/pca_fit.h"

namespace skinstream {

bool PcaFit::fit(const MarkerPcaModel& model, std::span<const int> slots, std::span<const Vec3> local) {
  const int components = static_cast<int>(model.variance.size());
  coefficients_.resize(components);
  if (components == 0) return true;
  const int rows = 3 * static_cast<int>(slots.size());
  PcaMatrix b(rows, components);
  PcaVector z(rows);
  for (size_t o = 0; o < slots.size(); ++o) {
    b.middleRows<3>(3 * o) = model.basis.middleRows<3>(3 * slots[o]);
    z.segment<3>(3 * o) = local[o] - model.mean.segment<3>(3 * slots[o]);
  }
  PcaMatrix normal(components, components);
  normal.noalias() = b.transpose().lazyProduct(b);  // small: no blocked GEMM
  for (int c = 0; c < components; ++c) normal(c, c) += model.residual_variance / model.variance(c);
  PcaVector rhs(components);
  rhs.noalias() = b.transpose().lazyProduct(z);
  llt_.compute(normal);
  if (llt_.info() != Eigen::Success) return false;
  coefficients_ = llt_.solve(rhs);
  return true;
}

bool PcaFit::factor_slots(const MarkerPcaModel& model, std::span<const int> slots, std::span<double> out_factor) {
  const int components = static_cast<int>(model.variance.size());
  PcaMatrix normal = PcaMatrix::Zero(components, components);
  for (int slot : slots) normal.noalias() += model.basis.middleRows<3>(3 * slot).transpose().lazyProduct(model.basis.middleRows<3>(3 * slot));
  for (int c = 0; c < components; ++c) normal(c, c) += model.residual_variance / model.variance(c);
  const Eigen::LLT<Eigen::Ref<PcaMatrix>> llt(normal);  // in place
  if (llt.info() != Eigen::Success) return false;
  Eigen::Map<Eigen::MatrixXd>(out_factor.data(), components, components) = normal.triangularView<Eigen::Lower>();
  return true;
}

void PcaFit::fit_factored(const MarkerPcaModel& model, std::span<const int> slots, std::span<const Vec3> local,
                          std::span<const double> factor) {
  const int components = static_cast<int>(model.variance.size());
  coefficients_.setZero(components);
  for (size_t o = 0; o < slots.size(); ++o)
    coefficients_.noalias() += model.basis.middleRows<3>(3 * slots[o]).transpose() * (local[o] - model.mean.segment<3>(3 * slots[o]));
  const Eigen::Map<const Eigen::MatrixXd> l(factor.data(), components, components);
  l.triangularView<Eigen::Lower>().solveInPlace(coefficients_);
  l.triangularView<Eigen::Lower>().transpose().solveInPlace(coefficients_);
}

Vec3 PcaFit::reconstruct(const MarkerPcaModel& model, int slot) const {
  Vec3 p = model.mean.segment<3>(3 * slot);
  for (Eigen::Index k = 0; k < coefficients_.size(); ++k) p += model.basis.block<3, 1>(3 * slot, k) * coefficients_(k);
  return p;
}

double PcaFit::squared_miss(const MarkerPcaModel& model, std::span<const int> slots, std::span<const Vec3> local) const {
  double miss = 0.0;
  for (size_t o = 0; o < slots.size(); ++o) miss += (local[o] - reconstruct(model, slots[o])).squaredNorm();
  return miss;
}

double PcaFit::predictive_variance(const MarkerPcaModel& model, int slot) const {
  if (coefficients_.size() == 0) return model.residual_variance;
  // trace(B_s A^-1 B_s^T) = |L^-1 B_s^T|^2 with A = L L^T: one triangular solve.
  Eigen::Matrix<double, Eigen::Dynamic, 3, 0, kMaxRingDims, 3> rows = model.basis.middleRows<3>(3 * slot).transpose();
  llt_.matrixL().solveInPlace(rows);
  return model.residual_variance * (1.0 + rows.squaredNorm() / 3.0);
}

}  // namespace skinstream
