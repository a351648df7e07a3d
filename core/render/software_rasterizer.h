#pragma once
// A small headless z-buffer rasteriser for looking at meshes without a GPU: reports, side by
// side comparisons of deformation methods, and error heat maps. Pure (no I/O): it fills an RGB8
// image in memory; protocol/research/png_file.h writes it out.
//
// Conventions: images are row-major with the top row first; meshes use skinstream's axes
// (millimetres, Z up, the subject faces +Y); triangles are counter-clockwise seen from outside.
// Speed matters only enough for offline use (a 53k-vertex mesh at 640x480 well under a second);
// every call allocates its own buffers.
#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/capture.h"

namespace skinstream::render {

struct Rgb {
  std::uint8_t r = 0, g = 0, b = 0;
  friend bool operator==(const Rgb&, const Rgb&) = default;
};

struct Image {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgb;  // 3 bytes per pixel, row-major, top row first

  Image() = default;
  Image(int w, int h, Rgb fill);
  Rgb at(int x, int y) const {
    const size_t i = 3 * (static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x));
    return {rgb[i], rgb[i + 1], rgb[i + 2]};
  }
  void set(int x, int y, Rgb c) {
    const size_t i = 3 * (static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x));
    rgb[i] = c.r;
    rgb[i + 1] = c.g;
    rgb[i + 2] = c.b;
  }
};

// A view of the mesh to draw; the data must outlive the call. normals (one per vertex, unit) are
// computed from the faces (area-weighted) when empty; colours (one per vertex) override colour.
struct RenderMesh {
  RenderMesh() = default;
  RenderMesh(std::span<const Vec3> v, std::span<const std::array<int, 3>> f) : vertices(v), faces(f) {}

  std::span<const Vec3> vertices;
  std::span<const std::array<int, 3>> faces;
  std::span<const Vec3> normals;
  std::span<const Rgb> colours;
  Rgb colour{200, 200, 200};
};

enum class Projection { perspective, orthographic };

// A look-at camera. The vertical field of view sets the perspective frustum; an orthographic
// camera shows the same extent at the target's distance (height 2 |target - eye| tan(fov/2)),
// so switching projection keeps the subject framed.
struct Camera {
  Vec3 eye{0.0, 1.0, 0.0};
  Vec3 target{0.0, 0.0, 0.0};
  Vec3 up{0.0, 0.0, 1.0};
  double vertical_fov_degrees = 30.0;
  Projection projection = Projection::perspective;
  int width = 640;
  int height = 480;
};

enum class Shading { flat, gouraud };

struct RenderOptions {
  Shading shading = Shading::gouraud;
  Rgb background{255, 255, 255};
  double ambient = 0.25;  // Lambert with a headlight: colour * (ambient + diffuse * max(0, n.l))
  double diffuse = 0.75;
  // Culled back faces are not drawn; otherwise they are lit two-sided (normal flipped towards
  // the camera), which shows the inside of open meshes.
  bool cull_back_faces = true;
};

// Throws std::invalid_argument for an image size of zero, a degenerate camera (eye at the
// target, up along the view direction, fov outside (0, 180)), or a face index out of range or
// a normals/colours count that does not match the vertices.
Image render_mesh(const RenderMesh& mesh, const Camera& camera, const RenderOptions& options = {});

// Unit per-vertex normals: the area-weighted sum of the incident faces' normals (+Z for a vertex
// with no face or only degenerate ones).
std::vector<Vec3> vertex_normals(std::span<const Vec3> vertices, std::span<const std::array<int, 3>> faces);

// Named views of a subject in skinstream axes: front looks from +Y towards -Y (the subject faces
// +Y), back from -Y, side from +X (the subject's right side; its left is -X), top from +Z looking down
// with +Y (the subject's front) at the top of the image.
enum class View { front, back, side, top };
std::optional<View> parse_view(std::string_view name);  // "front", "back", "side", "top"

// A camera looking at the centre of the vertices' bounding box from `view`, far enough that the
// whole box fits with `margin` (1.1 = 10% spare) in a width x height image.
Camera frame_view(std::span<const Vec3> vertices, View view, int width, int height,
                  Projection projection = Projection::perspective, double vertical_fov_degrees = 30.0,
                  double margin = 1.1);

// Per-vertex error heat colours: 0 is blue, then cyan, green, yellow, and max_value and above red;
// a non-finite value (a vertex with no ground truth) is magenta.
Rgb heat_colour(double value, double max_value);
std::vector<Rgb> heat_colours(std::span<const double> values, double max_value);

// Text with a built-in 5x7 bitmap font (letters without case, digits, + - _ . , : ; / % ( ) = ' ! ?
// and space; any other character is drawn as a box), scaled by an integer factor. Each character
// is 6 * scale pixels wide; drawing is clipped to the image.
void draw_text(Image& image, int x, int y, std::string_view text, Rgb colour, int scale = 2);
int text_width(std::string_view text, int scale = 2);

// Images in a row, top-aligned, `gap` pixels apart, on `background`; with labels (one per image,
// empty ones allowed) a caption band is added below, each label centred under its image.
Image compose_side_by_side(std::span<const Image> images, std::span<const std::string> labels = {},
                           Rgb background = {255, 255, 255}, int gap = 8, Rgb text_colour = {0, 0, 0});

}  // namespace skinstream::render
