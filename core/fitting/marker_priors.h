#pragma once
// What the known marker sets say of a take's markers, as the actor fit takes it: each labelled
// marker's defined place on the template and how far it may slide (a point entry), or the skin
// it must stay on (a region entry), or nothing (a name no set knows: the fit attaches it where
// the posed template's surface is nearest).

#include <span>
#include <string>
#include <vector>

#include "core/body/body.h"
#include "core/fitting/actor_fit.h"
#include "core/fitting/marker_set.h"

namespace skinstream {

struct MarkerPriors {
  std::vector<MarkerPrior> priors;  // one per label
  std::string set_name;             // the set that names the most labels; empty: none names any
  int named = 0;                    // labels it names
  std::string description;          // describe_match's line, for reports
};

// labels: the take's labelled markers, in subject order; body and triangles: the template at
// rest (triangles = triangulate(body.faces)). Throws std::invalid_argument (one line) when a
// matched set's entry cannot be placed on this template (a bone it does not have).
MarkerPriors marker_priors(std::span<const std::string> labels, const Body& body, std::span<const Triangle> triangles,
                           std::span<const MarkerSet> sets);

}  // namespace skinstream
