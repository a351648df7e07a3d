#include "clients/skinstream/actor_render.h"

#include <algorithm>

#include "core/deform/mesh_edges.h"

namespace skinstream::cli {

namespace {

void add_dot(const Vec3& at, double radius, render::Rgb colour, std::vector<Vec3>& vertices,
             std::vector<Triangle>& triangles, std::vector<render::Rgb>& colours) {
  const int first = static_cast<int>(vertices.size());
  const Vec3 axes[6] = {Vec3::UnitX(), -Vec3::UnitX(), Vec3::UnitY(), -Vec3::UnitY(), Vec3::UnitZ(), -Vec3::UnitZ()};
  for (const Vec3& a : axes) {
    vertices.push_back(at + radius * a);
    colours.push_back(colour);
  }
  // The eight faces, counter-clockwise seen from outside.
  const int faces[8][3] = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  for (const auto& f : faces) triangles.push_back({first + f[0], first + f[1], first + f[2]});
}

}  // namespace

std::vector<render::Rgb> strain_colours(std::span<const Vec3> vertices, std::span<const Vec3> rest,
                                        std::span<const Triangle> triangles) {
  const std::vector<std::pair<int, int>> edges = unique_edges(triangles);
  std::vector<double> ratio;
  for (const auto& [i, j] : edges) ratio.push_back((vertices[i] - vertices[j]).norm() / std::max(1e-9, (rest[i] - rest[j]).norm()));
  std::vector<double> sorted = ratio;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<long>(sorted.size() / 2), sorted.end());
  const double scale = sorted[sorted.size() / 2];
  std::vector<double> worst(vertices.size(), 1.0);
  for (size_t e = 0; e < edges.size(); ++e) {
    const double r = ratio[e] / scale, s = std::max(r, 1.0 / r);
    worst[edges[e].first] = std::max(worst[edges[e].first], s);
    worst[edges[e].second] = std::max(worst[edges[e].second], s);
  }
  for (double& w : worst) w -= 1.0;
  return render::heat_colours(worst, 0.5);
}

render::Image render_actor(std::span<const Vec3> vertices, std::span<const Triangle> triangles, const MarkerDots& dots,
                           const std::string& caption, int height, std::span<const render::Rgb> vertex_colours) {
  std::vector<Vec3> all(vertices.begin(), vertices.end());
  std::vector<Triangle> faces(triangles.begin(), triangles.end());
  std::vector<render::Rgb> colours(all.size(), render::Rgb{205, 190, 175});
  if (vertex_colours.size() == colours.size()) std::copy(vertex_colours.begin(), vertex_colours.end(), colours.begin());
  for (const Vec3& p : dots.measured) add_dot(p, 14.0, {40, 170, 60}, all, faces, colours);
  for (const Vec3& p : dots.withheld) add_dot(p, 16.0, {220, 40, 40}, all, faces, colours);
  for (const Vec3& p : dots.predicted) add_dot(p, 16.0, {40, 80, 230}, all, faces, colours);
  render::RenderMesh mesh(all, faces);
  mesh.colours = colours;
  const int width = height * 3 / 4;
  std::vector<render::Image> views;
  for (render::View view : {render::View::front, render::View::side}) {
    const render::Camera camera = render::frame_view(vertices, view, width, height);
    views.push_back(render::render_mesh(mesh, camera));
  }
  return render::compose_side_by_side(views, std::vector<std::string>{caption, ""});
}

}  // namespace skinstream::cli
