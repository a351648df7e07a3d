#include "core/render/software_rasterizer.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <tuple>

namespace skinstream::render {

namespace {

struct CameraFrame {
  Vec3 forward, right, up;  // right-handed: right = forward x up
};

CameraFrame camera_frame(const Camera& camera) {
  const Vec3 view = camera.target - camera.eye;
  if (!(view.norm() > 0.0)) throw std::invalid_argument("render: the camera's eye is at its target");
  CameraFrame f;
  f.forward = view.normalized();
  const Vec3 right = f.forward.cross(camera.up);
  if (!(right.norm() > 1e-9 * camera.up.norm())) throw std::invalid_argument("render: the camera's up is along its view");
  f.right = right.normalized();
  f.up = f.right.cross(f.forward);
  return f;
}

Eigen::Vector3f to_float(Rgb c) { return {static_cast<float>(c.r), static_cast<float>(c.g), static_cast<float>(c.b)}; }

Rgb to_rgb(const Eigen::Vector3f& c) {
  auto channel = [](float v) { return static_cast<std::uint8_t>(std::lround(std::clamp(v, 0.0f, 255.0f))); };
  return {channel(c.x()), channel(c.y()), channel(c.z())};
}

// A vertex after projection: pixel coordinates (x right, y down, pixel centres at +0.5) and the
// depth along the view direction.
struct ScreenVertex {
  double x = 0.0, y = 0.0, depth = 0.0;
};

double edge(double ax, double ay, double bx, double by, double px, double py) {
  // Two triangles sharing an edge see it in opposite directions. Evaluated as written, a*b - c*d
  // is not exactly antisymmetric once the compiler fuses one product into an FMA, and a pixel
  // centre on the edge then falls between both triangles (a hole along the diagonal of a quad).
  // Evaluating every edge from its lower endpoint and negating keeps the two results exact
  // negatives of each other, whatever the rounding.
  if (std::tie(bx, by) < std::tie(ax, ay)) return -edge(bx, by, ax, ay, px, py);
  return (bx - ax) * (py - ay) - (by - ay) * (px - ax);
}

}  // namespace

Image::Image(int w, int h, Rgb fill) : width(w), height(h), rgb(3 * static_cast<size_t>(w) * static_cast<size_t>(h)) {
  for (size_t i = 0; i < rgb.size(); i += 3) {
    rgb[i] = fill.r;
    rgb[i + 1] = fill.g;
    rgb[i + 2] = fill.b;
  }
}

std::vector<Vec3> vertex_normals(std::span<const Vec3> vertices, std::span<const std::array<int, 3>> faces) {
  std::vector<Vec3> normals(vertices.size(), Vec3::Zero());
  for (const auto& f : faces) {
    // The unnormalised cross product weights each face by its area.
    const Vec3 n = (vertices[f[1]] - vertices[f[0]]).cross(vertices[f[2]] - vertices[f[0]]);
    for (int v : f) normals[v] += n;
  }
  for (Vec3& n : normals) {
    const double length = n.norm();
    n = length > 0.0 && std::isfinite(length) ? Vec3(n / length) : Vec3::UnitZ();
  }
  return normals;
}

Image render_mesh(const RenderMesh& mesh, const Camera& camera, const RenderOptions& options) {
  if (camera.width <= 0 || camera.height <= 0) throw std::invalid_argument("render: image size must be positive");
  if (!(camera.vertical_fov_degrees > 0.0 && camera.vertical_fov_degrees < 180.0))
    throw std::invalid_argument("render: vertical field of view must be in (0, 180) degrees");
  const size_t n = mesh.vertices.size();
  if (!mesh.normals.empty() && mesh.normals.size() != n)
    throw std::invalid_argument("render: normals count differs from vertex count");
  if (!mesh.colours.empty() && mesh.colours.size() != n)
    throw std::invalid_argument("render: colours count differs from vertex count");
  for (const auto& f : mesh.faces)
    for (int v : f)
      if (v < 0 || static_cast<size_t>(v) >= n) throw std::invalid_argument("render: face index out of range");

  const CameraFrame frame = camera_frame(camera);
  const bool perspective = camera.projection == Projection::perspective;
  const double distance = (camera.target - camera.eye).norm();
  const double tan_half = std::tan(camera.vertical_fov_degrees * std::numbers::pi / 360.0);
  // Pixels per unit: at depth 1 for perspective, anywhere for orthographic.
  const double scale = 0.5 * camera.height / (perspective ? tan_half : distance * tan_half);
  const double near = 1e-6 * distance;
  const double cx = 0.5 * camera.width, cy = 0.5 * camera.height;

  Image image(camera.width, camera.height, options.background);
  if (mesh.faces.empty()) return image;

  std::vector<Vec3> computed_normals;
  std::span<const Vec3> normals = mesh.normals;
  if (normals.empty()) {
    computed_normals = vertex_normals(mesh.vertices, mesh.faces);
    normals = computed_normals;
  }

  // Per vertex: screen position, and the shaded colour seen from the front and from behind.
  std::vector<ScreenVertex> screen(n);
  std::vector<Eigen::Vector3f> lit_front(n), lit_back(n), base(n);
  for (size_t i = 0; i < n; ++i) {
    const Vec3 d = mesh.vertices[i] - camera.eye;
    ScreenVertex& s = screen[i];
    s.depth = d.dot(frame.forward);
    const double k = perspective ? scale / std::max(s.depth, near) : scale;
    s.x = cx + k * d.dot(frame.right);
    s.y = cy - k * d.dot(frame.up);
    // Headlight: light comes from the eye (along the view direction for orthographic).
    const Vec3 to_light = perspective ? Vec3(-d.normalized()) : Vec3(-frame.forward);
    const double cosine = normals[i].dot(to_light);
    base[i] = to_float(mesh.colours.empty() ? mesh.colour : mesh.colours[i]);
    lit_front[i] = base[i] * static_cast<float>(options.ambient + options.diffuse * std::max(0.0, cosine));
    lit_back[i] = base[i] * static_cast<float>(options.ambient + options.diffuse * std::max(0.0, -cosine));
  }

  std::vector<double> depth_buffer(static_cast<size_t>(camera.width) * static_cast<size_t>(camera.height),
                                   std::numeric_limits<double>::infinity());
  for (const auto& f : mesh.faces) {
    const ScreenVertex& a = screen[f[0]];
    const ScreenVertex& b = screen[f[1]];
    const ScreenVertex& c = screen[f[2]];
    // Triangles reaching behind a perspective eye are dropped rather than clipped.
    if (perspective && (a.depth <= near || b.depth <= near || c.depth <= near)) continue;
    const Vec3& p0 = mesh.vertices[f[0]];
    const Vec3 face_normal = (mesh.vertices[f[1]] - p0).cross(mesh.vertices[f[2]] - p0);
    const Vec3 to_eye = perspective ? Vec3(camera.eye - p0) : Vec3(-frame.forward);
    const bool front = face_normal.dot(to_eye) > 0.0;
    if (!front && options.cull_back_faces) continue;

    const double area = edge(a.x, a.y, b.x, b.y, c.x, c.y);
    if (!(std::abs(area) > 1e-12)) continue;
    const auto& lit = front ? lit_front : lit_back;
    Eigen::Vector3f flat_colour = Eigen::Vector3f::Zero();
    if (options.shading == Shading::flat) {
      const Vec3 centroid = (p0 + mesh.vertices[f[1]] + mesh.vertices[f[2]]) / 3.0;
      const Vec3 to_light = perspective ? Vec3((camera.eye - centroid).normalized()) : Vec3(-frame.forward);
      const double cosine = std::abs(face_normal.normalized().dot(to_light));  // facing already decided
      const Eigen::Vector3f colour = (base[f[0]] + base[f[1]] + base[f[2]]) / 3.0f;
      flat_colour = colour * static_cast<float>(options.ambient + options.diffuse * cosine);
    }

    const int x_min = std::max(0, static_cast<int>(std::floor(std::min({a.x, b.x, c.x}))));
    const int x_max = std::min(camera.width - 1, static_cast<int>(std::ceil(std::max({a.x, b.x, c.x}))));
    const int y_min = std::max(0, static_cast<int>(std::floor(std::min({a.y, b.y, c.y}))));
    const int y_max = std::min(camera.height - 1, static_cast<int>(std::ceil(std::max({a.y, b.y, c.y}))));
    // Perspective-correct interpolation weighs each corner by 1/depth.
    const double inv_depth[3] = {perspective ? 1.0 / a.depth : 1.0, perspective ? 1.0 / b.depth : 1.0,
                                 perspective ? 1.0 / c.depth : 1.0};
    for (int y = y_min; y <= y_max; ++y) {
      const double py = y + 0.5;
      for (int x = x_min; x <= x_max; ++x) {
        const double px = x + 0.5;
        double w0 = edge(b.x, b.y, c.x, c.y, px, py) / area;
        double w1 = edge(c.x, c.y, a.x, a.y, px, py) / area;
        double w2 = edge(a.x, a.y, b.x, b.y, px, py) / area;
        if (w0 < 0.0 || w1 < 0.0 || w2 < 0.0) continue;
        double depth = 0.0;
        if (perspective) {
          w0 *= inv_depth[0];
          w1 *= inv_depth[1];
          w2 *= inv_depth[2];
          const double sum = w0 + w1 + w2;
          depth = 1.0 / sum;
          w0 /= sum;
          w1 /= sum;
          w2 /= sum;
        } else {
          depth = w0 * a.depth + w1 * b.depth + w2 * c.depth;
        }
        double& stored = depth_buffer[static_cast<size_t>(y) * static_cast<size_t>(camera.width) + static_cast<size_t>(x)];
        if (!(depth < stored)) continue;
        stored = depth;
        const Eigen::Vector3f colour =
            options.shading == Shading::flat
                ? flat_colour
                : Eigen::Vector3f(lit[f[0]] * static_cast<float>(w0) + lit[f[1]] * static_cast<float>(w1) +
                                  lit[f[2]] * static_cast<float>(w2));
        image.set(x, y, to_rgb(colour));
      }
    }
  }
  return image;
}

std::optional<View> parse_view(std::string_view name) {
  if (name == "front") return View::front;
  if (name == "back") return View::back;
  if (name == "side") return View::side;
  if (name == "top") return View::top;
  return std::nullopt;
}

Camera frame_view(std::span<const Vec3> vertices, View view, int width, int height, Projection projection,
                  double vertical_fov_degrees, double margin) {
  if (vertices.empty()) throw std::invalid_argument("frame_view: no vertices");
  if (width <= 0 || height <= 0) throw std::invalid_argument("frame_view: image size must be positive");
  Vec3 low = vertices[0], high = vertices[0];
  for (const Vec3& v : vertices) {
    low = low.cwiseMin(v);
    high = high.cwiseMax(v);
  }
  const Vec3 centre = 0.5 * (low + high);
  Vec3 towards_eye = Vec3::UnitY(), up = Vec3::UnitZ();
  switch (view) {
    case View::front: towards_eye = Vec3::UnitY(); break;
    case View::back: towards_eye = -Vec3::UnitY(); break;
    case View::side: towards_eye = Vec3::UnitX(); break;
    case View::top:
      towards_eye = Vec3::UnitZ();
      up = Vec3::UnitY();
      break;
  }
  const Vec3 right = (-towards_eye).cross(up);
  // Half extents of the box across the image (right, up) and along the view.
  double half_w = 0.0, half_h = 0.0, half_depth = 0.0;
  for (int corner = 0; corner < 8; ++corner) {
    const Vec3 p((corner & 1) ? high.x() : low.x(), (corner & 2) ? high.y() : low.y(), (corner & 4) ? high.z() : low.z());
    const Vec3 d = p - centre;
    half_w = std::max(half_w, std::abs(d.dot(right)));
    half_h = std::max(half_h, std::abs(d.dot(up)));
    half_depth = std::max(half_depth, std::abs(d.dot(towards_eye)));
  }
  const double aspect = static_cast<double>(width) / height;
  const double tan_half = std::tan(vertical_fov_degrees * std::numbers::pi / 360.0);
  const double half_view = std::max({half_h, half_w / aspect, 1e-9}) * margin;
  // Perspective: the box's nearest face must fit; orthographic: the extent at the target does.
  const double distance =
      projection == Projection::perspective ? half_depth + half_view / tan_half : std::max(half_view / tan_half, 2.0 * half_depth);
  Camera camera;
  camera.target = centre;
  camera.eye = centre + distance * towards_eye;
  camera.up = up;
  camera.vertical_fov_degrees = vertical_fov_degrees;
  camera.projection = projection;
  camera.width = width;
  camera.height = height;
  return camera;
}

Rgb heat_colour(double value, double max_value) {
  if (!std::isfinite(value)) return {255, 0, 255};
  static const Eigen::Vector3f stops[5] = {{0, 0, 255}, {0, 255, 255}, {0, 255, 0}, {255, 255, 0}, {255, 0, 0}};
  const double t = max_value > 0.0 ? std::clamp(value / max_value, 0.0, 1.0) : (value > 0.0 ? 1.0 : 0.0);
  const double position = t * 4.0;
  const int i = std::min(3, static_cast<int>(position));
  const float s = static_cast<float>(position - i);
  return to_rgb(stops[i] * (1.0f - s) + stops[i + 1] * s);
}

std::vector<Rgb> heat_colours(std::span<const double> values, double max_value) {
  std::vector<Rgb> colours;
  colours.reserve(values.size());
  for (double v : values) colours.push_back(heat_colour(v, max_value));
  return colours;
}

namespace {

// The project's own 5x7 font: seven rows of five columns per glyph, '#' lit.
struct Glyph {
  char c;
  const char* rows[7];
};

constexpr Glyph kFont[] = {
    {'A', {".###.", "#...#", "#...#", "#####", "#...#", "#...#", "#...#"}},
    {'B', {"####.", "#...#", "#...#", "####.", "#...#", "#...#", "####."}},
    {'C', {".###.", "#...#", "#....", "#....", "#....", "#...#", ".###."}},
    {'D', {"####.", "#...#", "#...#", "#...#", "#...#", "#...#", "####."}},
    {'E', {"#####", "#....", "#....", "####.", "#....", "#....", "#####"}},
    {'F', {"#####", "#....", "#....", "####.", "#....", "#....", "#...."}},
    {'G', {".###.", "#...#", "#....", "#.###", "#...#", "#...#", ".####"}},
    {'H', {"#...#", "#...#", "#...#", "#####", "#...#", "#...#", "#...#"}},
    {'I', {".###.", "..#..", "..#..", "..#..", "..#..", "..#..", ".###."}},
    {'J', {"..###", "...#.", "...#.", "...#.", "...#.", "#..#.", ".##.."}},
    {'K', {"#...#", "#..#.", "#.#..", "##...", "#.#..", "#..#.", "#...#"}},
    {'L', {"#....", "#....", "#....", "#....", "#....", "#....", "#####"}},
    {'M', {"#...#", "##.##", "#.#.#", "#.#.#", "#...#", "#...#", "#...#"}},
    {'N', {"#...#", "#...#", "##..#", "#.#.#", "#..##", "#...#", "#...#"}},
    {'O', {".###.", "#...#", "#...#", "#...#", "#...#", "#...#", ".###."}},
    {'P', {"####.", "#...#", "#...#", "####.", "#....", "#....", "#...."}},
    {'Q', {".###.", "#...#", "#...#", "#...#", "#.#.#", "#..#.", ".##.#"}},
    {'R', {"####.", "#...#", "#...#", "####.", "#.#..", "#..#.", "#...#"}},
    {'S', {".####", "#....", "#....", ".###.", "....#", "....#", "####."}},
    {'T', {"#####", "..#..", "..#..", "..#..", "..#..", "..#..", "..#.."}},
    {'U', {"#...#", "#...#", "#...#", "#...#", "#...#", "#...#", ".###."}},
    {'V', {"#...#", "#...#", "#...#", "#...#", "#...#", ".#.#.", "..#.."}},
    {'W', {"#...#", "#...#", "#...#", "#.#.#", "#.#.#", "#.#.#", ".#.#."}},
    {'X', {"#...#", "#...#", ".#.#.", "..#..", ".#.#.", "#...#", "#...#"}},
    {'Y', {"#...#", "#...#", ".#.#.", "..#..", "..#..", "..#..", "..#.."}},
    {'Z', {"#####", "....#", "...#.", "..#..", ".#...", "#....", "#####"}},
    {'0', {".###.", "#...#", "#..##", "#.#.#", "##..#", "#...#", ".###."}},
    {'1', {"..#..", ".##..", "..#..", "..#..", "..#..", "..#..", ".###."}},
    {'2', {".###.", "#...#", "....#", "...#.", "..#..", ".#...", "#####"}},
    {'3', {"#####", "...#.", "..#..", "...#.", "....#", "#...#", ".###."}},
    {'4', {"...#.", "..##.", ".#.#.", "#..#.", "#####", "...#.", "...#."}},
    {'5', {"#####", "#....", "####.", "....#", "....#", "#...#", ".###."}},
    {'6', {"..##.", ".#...", "#....", "####.", "#...#", "#...#", ".###."}},
    {'7', {"#####", "....#", "...#.", "..#..", ".#...", ".#...", ".#..."}},
    {'8', {".###.", "#...#", "#...#", ".###.", "#...#", "#...#", ".###."}},
    {'9', {".###.", "#...#", "#...#", ".####", "....#", "...#.", ".##.."}},
    {'+', {".....", "..#..", "..#..", "#####", "..#..", "..#..", "....."}},
    {'-', {".....", ".....", ".....", "#####", ".....", ".....", "....."}},
    {'_', {".....", ".....", ".....", ".....", ".....", ".....", "#####"}},
    {'.', {".....", ".....", ".....", ".....", ".....", ".##..", ".##.."}},
    {',', {".....", ".....", ".....", ".....", ".##..", "..#..", ".#..."}},
    {':', {".....", ".##..", ".##..", ".....", ".##..", ".##..", "....."}},
    {';', {".....", ".##..", ".##..", ".....", ".##..", "..#..", ".#..."}},
    {'/', {".....", "....#", "...#.", "..#..", ".#...", "#....", "....."}},
    {'%', {"##...", "##..#", "...#.", "..#..", ".#...", "#..##", "...##"}},
    {'(', {"...#.", "..#..", ".#...", ".#...", ".#...", "..#..", "...#."}},
    {')', {".#...", "..#..", "...#.", "...#.", "...#.", "..#..", ".#..."}},
    {'=', {".....", ".....", "#####", ".....", "#####", ".....", "....."}},
    {'\'', {"..#..", "..#..", ".#...", ".....", ".....", ".....", "....."}},
    {'!', {"..#..", "..#..", "..#..", "..#..", "..#..", ".....", "..#.."}},
    {'?', {".###.", "#...#", "....#", "...#.", "..#..", ".....", "..#.."}},
    {' ', {".....", ".....", ".....", ".....", ".....", ".....", "....."}},
};

constexpr Glyph kUnknownGlyph = {'\0', {"#####", "#...#", "#...#", "#...#", "#...#", "#...#", "#####"}};

const Glyph& glyph(char c) {
  const char upper = (c >= 'a' && c <= 'z') ? static_cast<char>(c - 'a' + 'A') : c;
  for (const Glyph& g : kFont)
    if (g.c == upper) return g;
  return kUnknownGlyph;
}

}  // namespace

int text_width(std::string_view text, int scale) { return 6 * scale * static_cast<int>(text.size()); }

void draw_text(Image& image, int x, int y, std::string_view text, Rgb colour, int scale) {
  scale = std::max(1, scale);
  for (size_t k = 0; k < text.size(); ++k) {
    const Glyph& g = glyph(text[k]);
    const int left = x + static_cast<int>(k) * 6 * scale;
    for (int row = 0; row < 7; ++row)
      for (int column = 0; column < 5; ++column) {
        if (g.rows[row][column] != '#') continue;
        for (int dy = 0; dy < scale; ++dy)
          for (int dx = 0; dx < scale; ++dx) {
            const int px = left + column * scale + dx, py = y + row * scale + dy;
            if (px >= 0 && py >= 0 && px < image.width && py < image.height) image.set(px, py, colour);
          }
      }
  }
}

Image compose_side_by_side(std::span<const Image> images, std::span<const std::string> labels, Rgb background,
                           int gap, Rgb text_colour) {
  if (images.empty()) return Image(0, 0, background);
  constexpr int kScale = 2;
  constexpr int kPad = 6;
  const bool captions = std::any_of(labels.begin(), labels.end(), [](const std::string& l) { return !l.empty(); });
  int width = gap * static_cast<int>(images.size() - 1);
  int tallest = 0;
  for (const Image& im : images) {
    width += im.width;
    tallest = std::max(tallest, im.height);
  }
  const int band = captions ? 7 * kScale + 2 * kPad : 0;
  Image out(width, tallest + band, background);
  int left = 0;
  for (size_t k = 0; k < images.size(); ++k) {
    const Image& im = images[k];
    for (int y = 0; y < im.height; ++y)
      std::copy_n(im.rgb.begin() + 3 * static_cast<std::ptrdiff_t>(y) * im.width, 3 * im.width,
                  out.rgb.begin() + 3 * (static_cast<std::ptrdiff_t>(y) * width + left));
    if (k < labels.size() && !labels[k].empty()) {
      const int text_left = left + std::max(0, (im.width - text_width(labels[k], kScale)) / 2);
      draw_text(out, text_left, tallest + kPad, labels[k], text_colour, kScale);
    }
    left += im.width + gap;
  }
  return out;
}

}  // namespace skinstream::render
