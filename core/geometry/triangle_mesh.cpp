#include "core/geometry/triangle_mesh.h"

#include <Eigen/Geometry>  // cross()

namespace skinstream {

std::vector<Triangle> triangulate(const std::vector<Face>& faces, std::vector<int>* face_of) {
  std::vector<Triangle> out;
  out.reserve(faces.size() * 2);
  if (face_of) face_of->clear();
  for (size_t f = 0; f < faces.size(); ++f) {
    const Face& q = faces[f];
    out.push_back({q[0], q[1], q[2]});
    if (face_of) face_of->push_back(static_cast<int>(f));
    if (q[3] >= 0) {
      out.push_back({q[0], q[2], q[3]});
      if (face_of) face_of->push_back(static_cast<int>(f));
    }
  }
  return out;
}

Vec3 triangle_normal(const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 n = (b - a).cross(c - a);
  const double len = n.norm();
  return len > 0.0 ? Vec3(n / len) : Vec3(Vec3::Zero());
}

std::vector<Vec3> vertex_normals(const std::vector<Vec3>& points, const std::vector<Triangle>& triangles) {
  std::vector<Vec3> n(points.size(), Vec3::Zero());
  for (const Triangle& t : triangles) {
    const Vec3 area_n = (points[static_cast<size_t>(t[1])] - points[static_cast<size_t>(t[0])])
                            .cross(points[static_cast<size_t>(t[2])] - points[static_cast<size_t>(t[0])]);
    for (int i : t) n[static_cast<size_t>(i)] += area_n;
  }
  for (Vec3& v : n) {
    const double len = v.norm();
    if (len > 0.0) v /= len;
  }
  return n;
}

Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c,
                               Vec3* barycentric) {
  // Ericson, Real-Time Collision Detection, 5.1.5.
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  auto done = [&](double u, double v, double w) {
    if (barycentric) *barycentric = Vec3(u, v, w);
    return Vec3(u * a + v * b + w * c);
  };
  if (d1 <= 0.0 && d2 <= 0.0) return done(1, 0, 0);
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return done(0, 1, 0);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    const double v = d1 / (d1 - d3);
    return done(1 - v, v, 0);
  }
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return done(0, 0, 1);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    const double w = d2 / (d2 - d6);
    return done(1 - w, 0, w);
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return done(0, 1 - w, w);
  }
  const double denom = 1.0 / (va + vb + vc);
  const double v = vb * denom, w = vc * denom;
  return done(1 - v - w, v, w);
}

namespace {

// Six times the signed volume of the tetrahedron (a, b, c, d): positive when d is on the side
// of (a, b, c) its counter-clockwise normal points to.
double orient(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return (b - a).cross(c - a).dot(d - a);
}

// Segment p-q passes through the interior of triangle (a, b, c), by more than `tol` (a volume)
// on every side.
bool segment_crosses(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c, double tol) {
  const double sp = orient(a, b, c, p), sq = orient(a, b, c, q);
  if (!(sp > tol && sq < -tol) && !(sp < -tol && sq > tol)) return false;
  // The line through p and q meets the plane inside the triangle when it turns the same way
  // around all three edges.
  const double u = orient(p, q, a, b), v = orient(p, q, b, c), w = orient(p, q, c, a);
  return (u > tol && v > tol && w > tol) || (u < -tol && v < -tol && w < -tol);
}

}  // namespace

bool triangles_cross(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& b0, const Vec3& b1,
                     const Vec3& b2) {
  // Relative to a0, so that rounding scales with the triangles and not with their distance from
  // the origin; volumes within 1e-10 of the cube of their extent count as zero (touching or
  // coplanar: rounding would otherwise give either sign).
  const Vec3 p[6] = {Vec3::Zero(), a1 - a0, a2 - a0, b0 - a0, b1 - a0, b2 - a0};
  Eigen::Vector3d lo = p[0], hi = p[0];
  for (const Vec3& x : p) {
    lo = lo.cwiseMin(x);
    hi = hi.cwiseMax(x);
  }
  const double extent = (hi - lo).norm(), tol = 1e-10 * extent * extent * extent;
  // Two triangles in different planes meet along a segment whose ends lie on their edges, so
  // they cross exactly when one triangle's edge passes through the other.
  for (int k = 0; k < 3; ++k)
    if (segment_crosses(p[k], p[(k + 1) % 3], p[3], p[4], p[5], tol) ||
        segment_crosses(p[3 + k], p[3 + (k + 1) % 3], p[0], p[1], p[2], tol))
      return true;
  return false;
}

double signed_volume(const std::vector<Vec3>& points, const std::vector<Triangle>& triangles) {
  double v = 0.0;
  for (const Triangle& t : triangles)
    v += points[static_cast<size_t>(t[0])].dot(
        points[static_cast<size_t>(t[1])].cross(points[static_cast<size_t>(t[2])]));
  return v / 6.0;
}

}  // namespace skinstream
