#pragma once
// Pictures of an actor's deformed body with its markers, from the project's own rasteriser:
// front and side views side by side. Markers are drawn as small octahedra: measured ones
// green, withheld ones (measured) red, the surface's prediction of a withheld one blue.
#include <span>
#include <string>
#include <vector>

#include "core/capture.h"
#include "core/geometry/triangle_mesh.h"
#include "core/render/software_rasterizer.h"

namespace skinstream::cli {

struct MarkerDots {
  std::vector<Vec3> measured, withheld, predicted;
};

// colours: one per vertex (e.g. a heat map of the edge strain), or empty for skin colour.
render::Image render_actor(std::span<const Vec3> vertices, std::span<const Triangle> triangles, const MarkerDots& dots,
                           const std::string& caption, int height = 480, std::span<const render::Rgb> colours = {});

// Per vertex, the largest strain of its edges against `rest` (max(r, 1/r) of the length ratio,
// the median ratio removed), as heat colours: blue at 1, red at 1.5 and above.
std::vector<render::Rgb> strain_colours(std::span<const Vec3> vertices, std::span<const Vec3> rest,
                                        std::span<const Triangle> triangles);

}  // namespace skinstream::cli
