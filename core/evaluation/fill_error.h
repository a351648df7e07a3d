#pragma once
// How far a filler's output is from the truth on the samples it had to invent.

#include <string>
#include <vector>

#include "core/capture.h"
#include "core/evaluation/error_stats.h"
#include "core/evaluation/marker_region.h"

namespace skinstream {

struct RegionFillError {
  std::string region;      // one of marker_regions()
  ErrorStats millimetres;  // |filled - truth|
  ErrorStats normalised;   // |filled - truth| / normaliser[point]
};

struct FillErrorReport {
  ErrorStats millimetres;
  ErrorStats normalised;
  std::vector<RegionFillError> regions;  // only regions with samples, in marker_regions() order
  int unfilled = 0;                      // gap samples the filler left missing: not in any statistics
  int truth_missing = 0;                 // gap samples with no truth to compare with: not in any statistics
};

// Compares `filled` with `truth` at every sample of `gaps` (a sample covered by two gaps counts
// twice). `normaliser` has one positive value per channel, in the capture's channel order: the
// caller passes each marker's average distance to its one-ring neighbours in the reference pose,
// as Park & Hodgins normalise their Table 2; this function only divides by it. Regions come from
// marker_region(label) of the truth's labels.
// Throws std::invalid_argument when the captures differ in channel or frame count, when
// normaliser.size() != point count, when a gap's channel has a normaliser that is not positive and
// finite, or for a gap outside the capture.
FillErrorReport fill_error(const Capture& truth, const Capture& filled, const std::vector<Gap>& gaps,
                           const std::vector<double>& normaliser);

}  // namespace skinstream
