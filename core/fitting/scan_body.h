#pragma once
// A user's own scan (any mesh: no skeleton, its own vertex order, pose, unit and axes) made a
// body the actor fit can pose, through the template:
//   1. the template is fitted to the scan's surface as to a take of one frame whose markers are
//      points of the scan, each on the skin (actor_fit.h: its pose and proportions, each point
//      attached where the template's surface is nearest);
//   2. the fitted template is registered onto those points (Allen et al. 2003, with each point's
//      fitted place as its landmark and the data term for the rest), for the last millimetres;
//   3. each scan vertex inherits, from the nearest point of the registered template, the
//      template's skin weights over the segments;
//   4. the scan is unposed into the template's rest pose: each vertex goes to its place on the
//      fitted template at rest, plus its offset from that place in the scan's pose turned back
//      by the inverse of its blend of the segments' rotations; the segments' joints are the
//      fitted template's at rest. Posed from there, a scan starts from the rest pose the
//      template's skin weights and the fit's pose priors were made for. Skinned from its own
//      pose instead, a scan with its arms out above the horizontal stretched the training
//      take's edges to 26.8-28.8 typical edges and was refused on all three takes of
//      scripts/scan_table.py; unposed, 19.5-25.5, built on two.
// The marker sets' places, defined on the template, reach the scan the same way
// (transfer_priors). The scan keeps its own shape: the actor fit then poses it and places its
// markers, and proportions nothing.

#include <array>
#include <limits>
#include <span>
#include <vector>

#include "core/body/body.h"
#include "core/fitting/actor_fit.h"
#include "core/fitting/template_segments.h"
#include "core/offline/mesh_registration.h"

namespace skinstream {

struct ScanBodyOptions {
  int points = 2500;          // scan vertices the template is fitted and registered to
  ActorFitOptions fit = fit_defaults();
  RegistrationOptions registration;  // its offset is 0: the points are on the skin
  // The arms' elevations as the scan's frame measured them (left, right: degrees from hanging
  // straight down; NaN: unknown). The template is also fitted from its arms raised so, sideways
  // (fit.arm_starts), and the better fit kept.
  std::array<double, 2> arm_elevation_deg{std::numeric_limits<double>::quiet_NaN(),
                                          std::numeric_limits<double>::quiet_NaN()};

  static ActorFitOptions fit_defaults() {
    ActorFitOptions o;
    o.marker_offset_mm = 0.0;
    o.fit_frames = 1;
    o.rounds = 4;
    return o;
  }
};

struct ScanBody {
  FitBody body;                        // the scan, skinned (rest: its vertices unposed, mm, skinstream axes)
  std::vector<Vec3> as_given;          // the scan's vertices in its own pose
  std::vector<Vec3> template_on_scan;  // the template registered onto the scan (the template's topology)
  double fit_rms_mm = 0.0;             // the template fitted to the points, before registration
  double registered_rms_mm = 0.0;      // the points to the registered template's surface
  double inherited_median_mm = 0.0;    // scan vertices to the registered template, median
  double inherited_max_mm = 0.0;
  // Vertices whose blend of rotations could not be inverted (segments turned too far apart):
  // their offset was turned back by their heaviest segment's rotation alone.
  int unposed_by_one_segment = 0;
};

// scan: the scan's vertices in skinstream axes (mm, Z up, facing +Y, as to_skinstream_axes()
// gives them) and its triangles. Throws std::invalid_argument (one line) for an empty scan or one
// the template cannot be fitted to.
ScanBody skin_scan(const Body& template_body, const TemplateSegments& segments, std::span<const Vec3> scan,
                   std::span<const Triangle> scan_triangles, const ScanBodyOptions& options = {});

// Priors made on the template (marker_priors.h) carried to the scan: a defined place goes to the
// scan's surface point nearest to where that place lies on the registered template; allowed
// triangles to the scan triangles nearest to theirs.
std::vector<MarkerPrior> transfer_priors(std::span<const MarkerPrior> template_priors,
                                         std::span<const Triangle> template_triangles, const ScanBody& scan);

}  // namespace skinstream
