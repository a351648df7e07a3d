#pragma once
// What the daemon checks of a subject's body when it loads a subject file, the way the builder
// checked it before writing (core/fitting/subject_checks.h has the builder's fuller checks, with
// the fitted template and the training take at hand): a body crumpled or sprayed against its
// rest shape, or markers nowhere near its skin, is refused before any renderer sees it.

#include <string>

#include "core/deform/deformation_model.h"
#include "core/subject_model.h"

namespace skinstream {

struct BodyPlausibilityLimits {
  double max_strain = 1.5;               // an edge strained beyond this either way ...
  double max_strained_fraction = 0.05;   // ... on at most this fraction of the edges (the builder's refusal)
  double max_flipped_fraction = 0.003;   // turned triangles (a real reference pose's creases turn ~0.1%)
  double max_edge_stretch = 25.0;        // in typical edges: a shard (a crease of linear blend skinning stays below)
  double max_median_marker_skin_mm = 30.0;  // the markers' median distance to the nearest vertex
};

// Empty when plausible; otherwise what is wrong, in one line. A model without rest vertices (a
// mesh registered as given, before subject file version 6) gets the marker check alone.
std::string implausible_body(const SubjectModel& subject, const DeformationModel& model,
                             const BodyPlausibilityLimits& limits = {});

}  // namespace skinstream
