#pragma once
// The MakeHuman template (the raw file and the skinned body), posed copies of it and generated
// shapes that are not bodies, for the fitting tests.
#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <vector>

#include "core/body/anatomy.h"
#include "core/body/skinning.h"
#include "core/capture.h"
#include "core/geometry/triangle_mesh.h"
#include "protocol/offline/makehuman.h"
#include "support/test_data.h"

namespace skinstream::test {

struct TemplateBody {
  ObjMesh file;                     // as shipped: decimetres, Y up, facing +Z
  std::vector<Triangle> triangles;  // of both (same vertex order)
  Body body;                        // skinstream axes, mm
  Anatomy anatomy;
};

inline const TemplateBody& template_body() {
  static const TemplateBody t = [] {
    TemplateBody b;
    const std::string dir = shared_path("data/meshes/makehuman");
    b.file = read_obj(dir + "/makehuman_hm08_body_only.obj");
    b.triangles = triangulate(b.file.faces);
    b.body = load_makehuman(dir);
    b.anatomy = Anatomy::from(b.body);
    return b;
  }();
  return t;
}

// The template skinned into a pose set up on a PoseBuilder (skinstream axes, mm).
template <class Setup>
std::vector<Vec3> posed_template(Setup&& setup) {
  const TemplateBody& t = template_body();
  PoseBuilder pose(t.body.skeleton, t.anatomy);
  setup(pose);
  return skin(t.body.rest, t.body.weights, pose_bones(t.body.skeleton, pose.pose()));
}

// Shoulder to wrist joint direction of one arm in a pose, as an angle from hanging straight down
// (degrees).
template <class Setup>
double true_arm_elevation(Side side, Setup&& setup) {
  const TemplateBody& t = template_body();
  PoseBuilder pose(t.body.skeleton, t.anatomy);
  setup(pose);
  const BoneTransforms bones = pose_bones(t.body.skeleton, pose.pose());
  const Vec3 shoulder =
      bones[static_cast<size_t>(t.anatomy.arm[side].upperarm)] * t.anatomy.shoulder_joint[side];
  const Vec3 wrist = bones[static_cast<size_t>(t.anatomy.arm[side].wrist)] * t.anatomy.wrist_joint[side];
  return std::acos(-(wrist - shoulder).normalized().z()) * 180.0 / M_PI;
}

struct Shape {
  std::vector<Vec3> vertices;
  std::vector<Triangle> triangles;
};

// A grid of nu x nv quads mapped by f(s, t), s and t in [0, 1]; wrap joins the last column to the
// first.
template <class F>
void add_grid(Shape& m, int nu, int nv, bool wrap, F f) {
  const int base = static_cast<int>(m.vertices.size()), columns = wrap ? nu : nu + 1;
  for (int j = 0; j <= nv; ++j)
    for (int i = 0; i < columns; ++i)
      m.vertices.push_back(f(static_cast<double>(i) / nu, static_cast<double>(j) / nv));
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const int i1 = wrap ? (i + 1) % nu : i + 1;
      const int a = base + j * columns + i, b = base + j * columns + i1, c = base + (j + 1) * columns + i1,
                d = base + (j + 1) * columns + i;
      m.triangles.push_back({a, b, c});
      m.triangles.push_back({a, c, d});
    }
}

inline Shape sphere(double radius) {
  Shape m;
  add_grid(m, 48, 24, true, [&](double s, double t) {
    const double polar = M_PI * t, around = 2.0 * M_PI * s;
    return Vec3(radius * Vec3(std::sin(polar) * std::cos(around), std::sin(polar) * std::sin(around),
                              -std::cos(polar)));
  });
  return m;
}

// A sphere with smooth random bumps of about a fifth of its radius.
inline Shape blob(double radius, unsigned seed) {
  std::mt19937 random(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  double a[4][4];
  for (auto& row : a)
    for (double& x : row) x = normal(random);
  Shape m = sphere(radius);
  for (Vec3& p : m.vertices) {
    const Vec3 u = p.normalized();
    double bump = 0.0;
    for (int i = 0; i < 4; ++i)
      bump += 0.12 * (a[i][0] * std::sin((i + 1) * u.x() + a[i][1]) * std::cos((i + 1) * u.y() + a[i][2]) +
                      a[i][3] * u.z() * u.x());
    p *= 1.0 + bump;
  }
  return m;
}

inline Shape box(const Vec3& size) {
  Shape m;
  for (int axis = 0; axis < 3; ++axis)
    for (double sign : {-1.0, 1.0}) {
      const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
      add_grid(m, 16, 16, false, [&](double s, double t) {
        Vec3 p;
        p[axis] = 0.5 * sign * size[axis];
        p[a1] = (s - 0.5) * size[a1];
        p[a2] = (t - 0.5) * size[a2] * sign;
        return p;
      });
    }
  return m;
}

inline Shape cylinder(double radius, double length) {  // closed, axis z
  Shape m;
  add_grid(m, 48, 40, true, [&](double s, double t) {
    return Vec3(radius * std::cos(2.0 * M_PI * s), radius * std::sin(2.0 * M_PI * s), length * t);
  });
  for (double z : {0.0, length})
    add_grid(m, 48, 8, true, [&](double s, double t) {
      return Vec3(radius * t * std::cos(2.0 * M_PI * s), radius * t * std::sin(2.0 * M_PI * s), z);
    });
  return m;
}

inline Shape plane(double width, double length) {  // flat in z = 0
  Shape m;
  add_grid(m, 30, 60, false, [&](double s, double t) { return Vec3((s - 0.5) * width, t * length, 0.0); });
  return m;
}

}  // namespace skinstream::test
