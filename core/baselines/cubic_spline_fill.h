#pragma once
// Reference gap filler: an interpolating cubic spline through each channel's present samples,
// the usual "spline fill" of motion-capture tools. Good on short gaps, drifts on long ones.

#include "core/capture.h"

namespace skinstream {

enum class SplineEnd {
  // Third derivative continuous at the second and second-to-last knot. Reproduces any cubic
  // polynomial exactly (MATLAB spline / SciPy CubicSpline default), so it is the default.
  not_a_knot,
  // Zero second derivative at the first and last knot. Not exact even on a parabola; its error
  // from the end condition decays by ~0.27 per knot towards the gap.
  natural,
};

struct CubicSplineOptions {
  // Present samples used on each side of a gap. The spline is fitted locally so long captures
  // stay cheap; 10 knots per side keep the end-condition effect at the gap negligible.
  int window = 10;
  SplineEnd end = SplineEnd::not_a_knot;
};

// Returns a copy of `capture` with every labelled channel's missing samples filled. For each gap
// with present samples on both sides, one spline per coordinate passes through up to
// `options.window` present samples before the gap and as many after it (knots at their frame
// indices; other gaps inside the window are simply not knots) and is evaluated at the gap's
// frames. With 2 knots in total the spline is the line through them; with 3 it is the parabola
// (not-a-knot) or the natural spline. Gaps at the start or end hold the nearest present sample;
// a channel never present stays missing; unlabelled channels are unchanged.
// Throws std::invalid_argument for window < 1 or positions that do not match labels x frames.
Capture fill_cubic_spline(const Capture& capture, const CubicSplineOptions& options = {});

}  // namespace skinstream
