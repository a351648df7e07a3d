#pragma once
// Known marker sets by name: where each named marker of a capture sits on the body template.
// A capture labels its markers with a vendor's set (Vicon Plug-in Gait "LELB", OptiTrack Motive
// "LElbowOut", Qualisys "LElbowOut" behind a "Q_" prefix...); the actor fit starts each named
// marker at its place on the template instead of at the nearest surface point.
//
// A set holds placements of two kinds:
//   - a point entry names one marker (and its aliases) and puts it on the template's skin at
//     rest: a ray leaves the point `along` the bone's axis (0 = head joint, 1 = tail joint) in
//     `direction`, and the first place where it exits the surface is the marker's site (on the
//     skin; the fit adds the marker's height above it). `radius_mm` is how far the fit may slide
//     the marker from there.
//   - a region entry names many markers by a glob `pattern` ("thigh_L_*", '*' any run of
//     characters) and only restricts them to the skin skinned mostly by `bones` (names, or globs
//     such as "upperleg*.L"), optionally its front or back: a dense grid has no fixed points.
// The shipped sets are JSON files in config/marker_sets/ (format: docs/marker-sets.md; reader:
// protocol/offline/marker_set_file.h).
//
// Body axes at the template's rest pose (core/body/skeleton.h): millimetres, +X the subject's
// right, +Y forward, +Z up.
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/body/body.h"
#include "core/geometry/triangle_bvh.h"

namespace skinstream {

// Region entries' sides: the part of the surface facing forward (+Y) or backward.
inline constexpr int kAnySide = 0;
inline constexpr int kFrontSide = 1;
inline constexpr int kBackSide = -1;

struct MarkerPlacement {
  std::string name;  // a point entry: one marker
  std::vector<std::string> aliases;
  std::string description;
  std::string bone;
  double along = 0.5;              // 0 = the bone's head joint, 1 = its tail joint
  Vec3 direction = Vec3::UnitY();  // rest-pose body axes; any length but zero
  double radius_mm = 30.0;         // how far the fit may slide the marker from its site
  std::string pattern;             // a region entry (pattern non-empty): many markers
  std::vector<std::string> bones;  // names or globs of the bones that skin the region
  int side = kAnySide;             // kAnySide, kFrontSide or kBackSide

  bool is_region() const { return !pattern.empty(); }
};

struct MarkerSet {
  std::string name, source;  // what the set is; where its names and placements come from
  std::vector<MarkerPlacement> markers;
};

// Checks a set before use. Throws std::invalid_argument, one line naming the set and the entry:
// no name or source, no markers; a marker name, alias or pattern that is empty, not printable
// ASCII, holds a space, ':' or (outside patterns) '*', or repeats another of the set (case
// ignored, as captures are matched); a name or alias that a pattern of the set also matches; a
// point entry without a bone, with `along` outside [0, 1], a zero or non-finite direction or
// `radius_mm` outside (0, 500]; a region entry without '*' or without bones, with a point
// entry's fields (name, aliases, bone) or a side other than the three above.
void validate(const MarkerSet& set);

// A capture label without its subject prefix and surrounding spaces: "Actor1:LELB" -> "LELB"
// (Vicon, Motive's C3D and CSV exports write "Subject:Marker"). Prefixes joined with '_'
// (QTM's "Q_LElbowOut", NatNet's "Karlie_LElbowOut") cannot be told from names that hold '_'
// ("thigh_L_3"); match_marker_set tries them.
std::string bare_label(std::string_view label);

struct MarkerSetMatch {
  int set = -1;                // index into the sets; -1 when no set names any label
  std::vector<int> placement;  // per label: index into that set's markers, -1 = unknown
  int matched = 0;             // labels the set names
  int labelled = 0;            // labels that name something (not empty nor an unlabelled "*N")
  // Whether the set names at least half of the labelled markers: below that the capture is
  // taken for an unknown set (its few named markers may still use their placements).
  bool known() const { return set >= 0 && 2 * matched >= labelled && labelled > 0; }
};

// The set that names the most labels (ties: the set with fewer entries, then the first). A label
// is compared without its prefix (bare_label), case ignored, with the set's names and aliases,
// then with its region patterns; when nothing matches, the parts after each '_' are tried,
// longest first ("Q_LElbowOut" -> "LElbowOut"). Unlabelled channels ("*0", "") match nothing.
// The sets must be valid (validate()).
MarkerSetMatch match_marker_set(std::span<const MarkerSet> sets, std::span<const std::string> labels);

// One line for a report: "Vicon Plug-in Gait (full body): 39 of 39 labelled markers named", or
// for an unknown set the best candidate's count and the first unnamed labels.
std::string describe_match(std::span<const MarkerSet> sets, std::span<const std::string> labels,
                           const MarkerSetMatch& match);

// A place on the template's surface: a triangle, the barycentric weights of its three vertices,
// the point (mm) and the triangle's unit outward normal.
struct SurfacePoint {
  int triangle = -1;
  Vec3 barycentric = Vec3::Zero();
  Vec3 position = Vec3::Zero();
  Vec3 normal = Vec3::Zero();
};

// Where a point entry lands on the body at rest: the first exit of its ray through the surface
// (the first crossing of a triangle facing along the ray: a ray that starts outside the body
// passes in and takes the exit after that). `triangles`: the body's surface (e.g.
// triangulate(body.faces)); `bvh`: built over body.rest and those triangles.
// Throws std::invalid_argument (one line naming the marker) for a region entry, a bone the
// skeleton does not have, `along` or the direction invalid as in validate(), or a ray that never
// leaves the body.
SurfacePoint place_marker(const Body& body, std::span<const Triangle> triangles, const TriangleBvh& bvh,
                          const MarkerPlacement& placement);

// For a region entry, one flag per triangle (1 = in the region): triangles with a vertex whose
// dominant skin weight (SkinWeights::dominant) is on one of the entry's bones and, with a side,
// whose vertex normal faces that way (n.y >= -0.1 for the front, below for the back: the rule
// the project's dense layout names its regions by, core/synth/marker_layout.h).
// Throws std::invalid_argument (one line naming the pattern) for a point entry, a bone name or
// glob the skeleton does not have, or weights that are not one row per vertex.
std::vector<char> region_triangles(const Body& body, std::span<const Triangle> triangles,
                                   const MarkerPlacement& placement);

}  // namespace skinstream
