#pragma once
// How much each point's error moves a rigid fit's estimate (eq. 2): for the fit of `source`
// (local coordinates, the estimated marker at the origin) onto measured targets, the change of
// the fitted origin per unit change of target k, to first order. A member far from the marker,
// or a fit resting on few or nearly collinear members, turns small errors into large ones.

#include <span>

#include "core/capture.h"

namespace skinstream {

// out_leverage[k] = |J_k|_F^2 / 3, J_k the 3x3 derivative of the fitted origin with respect to
// target k: an isotropic error of variance v per coordinate on target k adds v * out_leverage[k]
// per coordinate to the estimate. Marker at the centroid of n points: 1 / n^2 each. Spans of
// equal length, at least one point; nearly collinear points get large (finite) leverages.
void rigid_fit_leverage(std::span<const Vec3> source, std::span<double> out_leverage);

}  // namespace skinstream
