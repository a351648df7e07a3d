#include "core/render/software_rasterizer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace skinstream::render {
namespace {

using Triangles = std::vector<std::array<int, 3>>;

const Rgb kWhite{255, 255, 255};

// The cube [-0.5, 0.5]^3 with outward, counter-clockwise triangles.
struct Cube {
  std::vector<Vec3> vertices;
  Triangles faces;
  Cube() {
    for (int i = 0; i < 8; ++i) vertices.emplace_back(i & 1 ? 0.5 : -0.5, i & 2 ? 0.5 : -0.5, i & 4 ? 0.5 : -0.5);
    const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& q : quads) {
      faces.push_back({q[0], q[1], q[2]});
      faces.push_back({q[0], q[2], q[3]});
    }
  }
};

int count_not(const Image& im, Rgb background) {
  int n = 0;
  for (int y = 0; y < im.height; ++y)
    for (int x = 0; x < im.width; ++x) n += !(im.at(x, y) == background);
  return n;
}

// Looking from +Y at the origin, 5 units away, 100 x 100 pixels; at the target's distance the
// image spans 2 units (orthographic) so one unit is 50 pixels.
Camera front_camera(Projection projection) {
  Camera c;
  c.eye = Vec3(0, 5, 0);
  c.target = Vec3::Zero();
  c.up = Vec3::UnitZ();
  c.vertical_fov_degrees = 2.0 * std::atan(1.0 / 5.0) * 180.0 / std::numbers::pi;
  c.projection = projection;
  c.width = c.height = 100;
  return c;
}

TEST(SoftwareRasterizer, RejectsBadCamerasAndMeshes) {
  const Cube cube;
  RenderMesh mesh{cube.vertices, cube.faces};
  Camera c = front_camera(Projection::perspective);
  c.width = 0;
  EXPECT_THROW(render_mesh(mesh, c), std::invalid_argument);
  c = front_camera(Projection::perspective);
  c.target = c.eye;
  EXPECT_THROW(render_mesh(mesh, c), std::invalid_argument);
  c = front_camera(Projection::perspective);
  c.up = Vec3::UnitY();
  EXPECT_THROW(render_mesh(mesh, c), std::invalid_argument);
  c = front_camera(Projection::perspective);
  c.vertical_fov_degrees = 180.0;
  EXPECT_THROW(render_mesh(mesh, c), std::invalid_argument);
  const Triangles bad = {{0, 1, 8}};
  EXPECT_THROW(render_mesh(RenderMesh{cube.vertices, bad}, front_camera(Projection::perspective)), std::invalid_argument);
  const std::vector<Vec3> two_normals(2, Vec3::UnitY());
  mesh.normals = two_normals;
  EXPECT_THROW(render_mesh(mesh, front_camera(Projection::perspective)), std::invalid_argument);
}

TEST(SoftwareRasterizer, EmptyMeshGivesTheBackground) {
  RenderOptions options;
  options.background = {10, 20, 30};
  const Image im = render_mesh(RenderMesh{}, front_camera(Projection::perspective), options);
  EXPECT_EQ(im.width, 100);
  EXPECT_EQ(im.height, 100);
  EXPECT_EQ(count_not(im, {10, 20, 30}), 0);
}

TEST(SoftwareRasterizer, OrthographicCubeCoversExactlyItsSquare) {
  const Cube cube;
  RenderOptions flat;
  flat.shading = Shading::flat;  // smooth normals would round the cube's shading
  const Image im = render_mesh(RenderMesh{cube.vertices, cube.faces}, front_camera(Projection::orthographic), flat);
  // One unit is 50 pixels: the cube's front face covers columns and rows 25..74.
  EXPECT_EQ(count_not(im, kWhite), 50 * 50);
  for (int y = 0; y < 100; ++y)
    for (int x = 0; x < 100; ++x)
      ASSERT_EQ(!(im.at(x, y) == kWhite), x >= 25 && x < 75 && y >= 25 && y < 75) << x << "," << y;
  // The face looks straight at the headlight: fully lit everywhere (ambient + diffuse = 1).
  EXPECT_EQ(im.at(50, 50), (Rgb{200, 200, 200}));
  EXPECT_EQ(im.at(26, 73), (Rgb{200, 200, 200}));
}

TEST(SoftwareRasterizer, PerspectiveCubeShowsItsNearFaceLarger) {
  const Cube cube;
  RenderOptions flat;
  flat.shading = Shading::flat;
  const Image im = render_mesh(RenderMesh{cube.vertices, cube.faces}, front_camera(Projection::perspective), flat);
  // The near face at depth 4.5 spans 0.5 * 5 / 4.5 units each side of centre: 27.8 pixels.
  const double half = 50.0 * 0.5 * 5.0 / 4.5;
  const int expected = static_cast<int>(std::lround(4 * half * half));
  EXPECT_NEAR(count_not(im, kWhite), expected, 4 * 2 * half);  // within one pixel round the edge
  EXPECT_FALSE(im.at(50 - 27, 50) == kWhite);
  EXPECT_TRUE(im.at(50 - 29, 50) == kWhite);
  EXPECT_FALSE(im.at(50, 50 + 27) == kWhite);
  EXPECT_TRUE(im.at(50, 50 + 29) == kWhite);
  // Flat shading of the face seen head-on: full colour at the centre.
  EXPECT_EQ(im.at(50, 50), (Rgb{200, 200, 200}));
}

TEST(SoftwareRasterizer, NearerTriangleHidesFartherOneWhateverTheOrder) {
  // Two overlapping triangles facing the camera (+Y): red nearer (y = 1), blue farther (y = -1).
  const std::vector<Vec3> v = {{-1, 1, -1}, {1, 1, -1}, {0, 1, 1}, {-1, -1, -1}, {1, -1, -1}, {0, -1, 1}};
  const Triangles near_first = {{0, 2, 1}, {3, 5, 4}};
  const Triangles far_first = {{3, 5, 4}, {0, 2, 1}};
  const std::vector<Rgb> colours = {{255, 0, 0}, {255, 0, 0}, {255, 0, 0}, {0, 0, 255}, {0, 0, 255}, {0, 0, 255}};
  RenderOptions options;
  options.ambient = 1.0;  // unshaded, to compare colours exactly
  options.diffuse = 0.0;
  for (Projection p : {Projection::perspective, Projection::orthographic}) {
    for (const Triangles* faces : {&near_first, &far_first}) {
      RenderMesh mesh{v, *faces};
      mesh.colours = colours;
      const Image im = render_mesh(mesh, front_camera(p), options);
      EXPECT_EQ(im.at(50, 50), (Rgb{255, 0, 0}));
    }
  }
}

TEST(SoftwareRasterizer, BackFacesAreCulledOrLitTwoSided) {
  // One triangle turned away from the camera (its normal points to -Y).
  const std::vector<Vec3> v = {{-1, 0, -1}, {1, 0, -1}, {0, 0, 1}};
  const Triangles away = {{0, 1, 2}};
  const Triangles towards = {{0, 2, 1}};
  RenderOptions cull;
  EXPECT_EQ(count_not(render_mesh(RenderMesh{v, away}, front_camera(Projection::perspective), cull), kWhite), 0);
  EXPECT_GT(count_not(render_mesh(RenderMesh{v, towards}, front_camera(Projection::perspective), cull), kWhite), 500);
  RenderOptions two_sided;
  two_sided.cull_back_faces = false;
  const Image back = render_mesh(RenderMesh{v, away}, front_camera(Projection::orthographic), two_sided);
  const Image front = render_mesh(RenderMesh{v, towards}, front_camera(Projection::orthographic), two_sided);
  EXPECT_EQ(back.at(50, 50), (Rgb{200, 200, 200}));  // lit as if it faced the camera
  EXPECT_EQ(back.rgb, front.rgb);
}

TEST(SoftwareRasterizer, GouraudFollowsVertexNormalsFlatDoesNot) {
  const std::vector<Vec3> v = {{-1, 0, -1}, {1, 0, -1}, {0, 0, 1}};
  const Triangles t = {{0, 2, 1}};
  // Normals tilted away from the camera at the bottom corners, facing it at the top.
  const std::vector<Vec3> normals = {Vec3(-1, 1, 0).normalized(), Vec3(1, 1, 0).normalized(), Vec3(0, 1, 0)};
  RenderMesh mesh{v, t};
  mesh.normals = normals;
  RenderOptions gouraud, flat;
  flat.shading = Shading::flat;
  const Image g = render_mesh(mesh, front_camera(Projection::orthographic), gouraud);
  const Image f = render_mesh(mesh, front_camera(Projection::orthographic), flat);
  // Near the top corner (row 26) Gouraud is brighter than near the bottom (row 73).
  EXPECT_GT(g.at(50, 27).r, g.at(30, 73).r);
  EXPECT_EQ(f.at(50, 27), f.at(30, 73));
  EXPECT_EQ(f.at(50, 50), (Rgb{200, 200, 200}));
}

TEST(SoftwareRasterizer, ComputedNormalsAreUnitAndOutward) {
  const Cube cube;
  const std::vector<Vec3> n = vertex_normals(cube.vertices, cube.faces);
  for (size_t i = 0; i < n.size(); ++i) {
    EXPECT_NEAR(n[i].norm(), 1.0, 1e-12);
    EXPECT_GT(n[i].dot(cube.vertices[i]), 0.5);  // points away from the centre
  }
  const std::vector<Vec3> lone = {Vec3::Zero()};
  EXPECT_EQ(vertex_normals(lone, {})[0], Vec3::UnitZ());
}

TEST(SoftwareRasterizer, OutputIsDeterministic) {
  const Cube cube;
  Camera c = front_camera(Projection::perspective);
  c.eye = Vec3(3.1, 4.2, 2.3);
  const Image a = render_mesh(RenderMesh{cube.vertices, cube.faces}, c);
  const Image b = render_mesh(RenderMesh{cube.vertices, cube.faces}, c);
  EXPECT_EQ(a.rgb, b.rgb);
  EXPECT_GT(count_not(a, kWhite), 1000);
}

TEST(SoftwareRasterizer, FramedViewsShowTheWholeBoxFromTheNamedSide) {
  EXPECT_EQ(parse_view("front"), View::front);
  EXPECT_EQ(parse_view("side"), View::side);
  EXPECT_EQ(parse_view("sideways"), std::nullopt);
  // A box 400 wide (X), 300 deep (Y), 1800 tall (Z), like a standing subject in mm.
  std::vector<Vec3> box;
  for (int i = 0; i < 8; ++i) box.emplace_back(i & 1 ? 200 : -200, i & 2 ? 1150 : 850, i & 4 ? 1800 : 0);
  const Camera front = frame_view(box, View::front, 300, 400);
  EXPECT_TRUE(front.target.isApprox(Vec3(0, 1000, 900)));
  EXPECT_GT(front.eye.y(), 1150.0);  // in front of the subject, who faces +Y
  EXPECT_NEAR(front.eye.x(), 0.0, 1e-9);
  EXPECT_NEAR(front.eye.z(), 900.0, 1e-9);
  const Camera side = frame_view(box, View::side, 300, 400);
  EXPECT_GT(side.eye.x(), 200.0);
  const Camera top = frame_view(box, View::top, 300, 400);
  EXPECT_GT(top.eye.z(), 1800.0);
  // Render the box from every view and projection: it fills the frame but never touches the border.
  const Cube cube;
  std::vector<Vec3> scaled;
  for (const Vec3& p : cube.vertices) scaled.push_back(Vec3(400 * p.x(), 1000 + 300 * p.y(), 900 + 1800 * p.z()));
  for (View view : {View::front, View::back, View::side, View::top})
    for (Projection p : {Projection::perspective, Projection::orthographic}) {
      const Image im = render_mesh(RenderMesh{scaled, cube.faces}, frame_view(scaled, view, 300, 400, p));
      int covered = count_not(im, kWhite);
      EXPECT_GT(covered, 300 * 400 / 20);
      for (int x = 0; x < 300; ++x) ASSERT_TRUE(im.at(x, 0) == kWhite && im.at(x, 399) == kWhite);
      for (int y = 0; y < 400; ++y) ASSERT_TRUE(im.at(0, y) == kWhite && im.at(299, y) == kWhite);
    }
}

TEST(SoftwareRasterizer, HeatColoursRunBlueToRedWithMagentaForMissing) {
  EXPECT_EQ(heat_colour(0.0, 5.0), (Rgb{0, 0, 255}));
  EXPECT_EQ(heat_colour(-1.0, 5.0), (Rgb{0, 0, 255}));
  EXPECT_EQ(heat_colour(2.5, 5.0), (Rgb{0, 255, 0}));
  EXPECT_EQ(heat_colour(5.0, 5.0), (Rgb{255, 0, 0}));
  EXPECT_EQ(heat_colour(50.0, 5.0), (Rgb{255, 0, 0}));
  EXPECT_EQ(heat_colour(std::nan(""), 5.0), (Rgb{255, 0, 255}));
  // Redness never decreases as the error grows.
  int last_red = -1;
  for (double e = 0; e <= 5.0; e += 0.05) {
    const Rgb c = heat_colour(e, 5.0);
    EXPECT_GE(c.r, last_red);
    last_red = c.r;
  }
  const std::vector<double> errors = {0.0, 10.0};
  EXPECT_EQ(heat_colours(errors, 10.0), (std::vector<Rgb>{{0, 0, 255}, {255, 0, 0}}));
}

TEST(SoftwareRasterizer, SideBySidePlacesImagesInARowWithCaptions) {
  const Image a(30, 20, {255, 0, 0}), b(50, 40, {0, 0, 255});
  const std::vector<Image> images = {a, b};
  const Image row = compose_side_by_side(images, {}, kWhite, 4);
  EXPECT_EQ(row.width, 84);
  EXPECT_EQ(row.height, 40);
  EXPECT_EQ(row.at(29, 19), (Rgb{255, 0, 0}));
  EXPECT_EQ(row.at(29, 20), kWhite);  // below the shorter image
  EXPECT_EQ(row.at(31, 0), kWhite);   // the gap
  EXPECT_EQ(row.at(34, 0), (Rgb{0, 0, 255}));
  EXPECT_EQ(row.at(83, 39), (Rgb{0, 0, 255}));

  const std::vector<std::string> labels = {"rigid+RBF", "truth"};
  const Image captioned = compose_side_by_side(images, labels, kWhite, 4);
  EXPECT_GT(captioned.height, 40);
  int ink_under_a = 0, ink_under_b = 0;
  for (int y = 40; y < captioned.height; ++y)
    for (int x = 0; x < captioned.width; ++x)
      if (captioned.at(x, y) == Rgb{0, 0, 0}) (x < 30 ? ink_under_a : ink_under_b)++;
  EXPECT_GT(ink_under_a, 40);
  EXPECT_GT(ink_under_b, 40);
  EXPECT_EQ(compose_side_by_side({}, {}).width, 0);
}

TEST(SoftwareRasterizer, BitmapFontDrawsKnownGlyphs) {
  Image im(20, 20, kWhite);
  draw_text(im, 0, 0, "l", {0, 0, 0}, 1);  // lower case is drawn as upper case
  // 'L': a vertical bar in column 0 and a full bottom row.
  for (int y = 0; y < 7; ++y) EXPECT_EQ(im.at(0, y), (Rgb{0, 0, 0}));
  for (int x = 0; x < 5; ++x) EXPECT_EQ(im.at(x, 6), (Rgb{0, 0, 0}));
  EXPECT_EQ(im.at(1, 0), kWhite);
  EXPECT_EQ(text_width("LBS", 2), 36);
  draw_text(im, 15, 15, "WWW", {0, 0, 0}, 3);  // clipped, no crash
}

}  // namespace
}  // namespace skinstream::render
