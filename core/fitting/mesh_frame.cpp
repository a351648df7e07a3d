#include "core/fitting/mesh_frame.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include "core/geometry/triangle_bvh.h"

namespace skinstream {

namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Detection constants, from the proportions of human bodies (fractions of the height).
constexpr int kSymmetrySamples = 1500;         // surface points mirrored per plane tried
constexpr double kTrimmed = 0.6;               // the closest 60% of mirrored points fit the plane
constexpr double kMaxSymmetryResidual = 0.01;  // median mirror distance: 17 mm on 1.7 m
constexpr double kSymmetryTie = 0.001;         // planes this close in residual mirror equally well
constexpr double kMinHeightToDepth = 2.0;      // a standing body is 4-6 times taller than deep
constexpr double kSnapDeg = 10.0;              // long axis this close to a file axis: that axis
constexpr double kLegGap = 0.005;              // no surface this close to the mirror plane: apart
constexpr double kMinLegSplit = 0.5;           // legs apart in at least half the low slices
constexpr double kMinSplitContrast = 0.25;     // and clearly more than at the other end
constexpr double kMinToeReach = 0.01;          // toes ahead of the ankle minus heels behind it
constexpr double kArmCut = 0.16;               // beyond the shoulders' and hips' half-width
constexpr double kMinArmArea = 0.005;          // of the surface, for an arm to be measured
constexpr double kNeckHalfWidth = 0.08;        // the neck and head are narrower (about 0.04)
constexpr double kShoulderDepth = 0.03;        // shoulder joint centre below the top of the shoulder
constexpr double kShoulderHalfWidth = 0.105;   // joint centre from the mirror plane
constexpr double kMinHeightMm = 500.0, kMaxHeightMm = 3000.0;  // less than a factor 10 apart

std::string text(const char* fmt, double a, double b = 0.0, double c = 0.0) {
  char buffer[200];
  std::snprintf(buffer, sizeof buffer, fmt, a, b, c);
  return buffer;
}

std::string vec_text(const Vec3& v) {
  const auto clean = [](double x) { return std::abs(x) < 1e-9 ? 0.0 : x; };  // no "-6e-18" or "-0"
  return text("(%.3g, %.3g, %.3g)", clean(v.x()), clean(v.y()), clean(v.z()));
}

std::string unit_text(double unit_mm) {
  if (unit_mm == 1.0) return "in millimetres";
  if (unit_mm == 10.0) return "in centimetres";
  if (unit_mm == 100.0) return "in decimetres";
  if (unit_mm == 1000.0) return "in metres";
  return text("at %.4g mm per unit", unit_mm);
}

// A plane n . p = d, n unit.
struct Plane {
  Vec3 n = Vec3::UnitX();
  double d = 0.0;
};

// The surface centred on its centroid and divided by its RMS radius: every threshold below is
// then free of the file's unit and placement.
struct Surface {
  std::vector<Vec3> points;
  std::vector<Triangle> triangles;
  std::vector<Vec3> centres, normals;  // per triangle
  std::vector<double> areas;
  double area = 0.0;
  std::vector<char> used;  // vertex of some triangle
  Vec3 centroid = Vec3::Zero();
  double scale = 1.0;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  std::vector<Vec3> samples;  // equal-area sample of triangle centres
  TriangleBvh bvh;

  Surface(std::span<const Vec3> vertices, std::span<const Triangle> tris);

  double lowest(const Vec3& dir) const {
    double lo = std::numeric_limits<double>::infinity();
    for (size_t v = 0; v < points.size(); ++v)
      if (used[v]) lo = std::min(lo, dir.dot(points[v]));
    return lo;
  }
  double extent(const Vec3& dir) const { return -lowest(-dir) - lowest(dir); }
};

Surface::Surface(std::span<const Vec3> vertices, std::span<const Triangle> tris)
    : triangles(tris.begin(), tris.end()) {
  if (vertices.empty() || tris.empty())
    throw std::invalid_argument("the mesh has no vertices or no triangles");
  for (size_t v = 0; v < vertices.size(); ++v)
    if (!is_present(vertices[v]))
      throw std::invalid_argument("mesh vertex " + std::to_string(v) + " is not finite");
  used.assign(vertices.size(), 0);
  for (size_t t = 0; t < tris.size(); ++t)
    for (int i : tris[t]) {
      if (i < 0 || static_cast<size_t>(i) >= vertices.size())
        throw std::invalid_argument("mesh triangle " + std::to_string(t) + " uses vertex " +
                                    std::to_string(i) + " of " + std::to_string(vertices.size()));
      used[static_cast<size_t>(i)] = 1;
    }
  // Centroid and covariance of the surface (triangle centres weighted by area), in file units
  // first, then the normalised copy.
  centres.resize(tris.size());
  areas.resize(tris.size());
  normals.resize(tris.size());
  for (size_t t = 0; t < tris.size(); ++t) {
    const Vec3 &a = vertices[static_cast<size_t>(tris[t][0])], &b = vertices[static_cast<size_t>(tris[t][1])],
               &c = vertices[static_cast<size_t>(tris[t][2])];
    centres[t] = (a + b + c) / 3.0;
    areas[t] = 0.5 * (b - a).cross(c - a).norm();
    area += areas[t];
    centroid += areas[t] * centres[t];
  }
  if (!(area > 0.0)) throw std::invalid_argument("the mesh has no area");
  centroid /= area;
  for (size_t t = 0; t < tris.size(); ++t) {
    const Vec3 r = centres[t] - centroid;
    covariance += areas[t] * r * r.transpose();
  }
  covariance /= area;
  scale = std::sqrt(covariance.trace());
  if (!(scale > 0.0)) throw std::invalid_argument("the mesh has no extent");
  covariance /= scale * scale;
  points.resize(vertices.size());
  for (size_t v = 0; v < vertices.size(); ++v) points[v] = (vertices[v] - centroid) / scale;
  area = 0.0;
  for (size_t t = 0; t < tris.size(); ++t) {
    const Vec3 &a = points[static_cast<size_t>(tris[t][0])], &b = points[static_cast<size_t>(tris[t][1])],
               &c = points[static_cast<size_t>(tris[t][2])];
    centres[t] = (a + b + c) / 3.0;
    areas[t] = 0.5 * (b - a).cross(c - a).norm();
    normals[t] = triangle_normal(a, b, c);
    area += areas[t];
  }
  // Equal-area samples: the centre of the triangle at each step of the cumulative area.
  const int n = std::min<int>(kSymmetrySamples, static_cast<int>(tris.size()));
  double cumulative = 0.0;
  size_t t = 0;
  for (int k = 0; k < n; ++k) {
    const double target = (k + 0.5) / n * area;
    while (t + 1 < tris.size() && cumulative + areas[t] < target) cumulative += areas[t++];
    samples.push_back(centres[t]);
  }
  bvh = TriangleBvh(points, triangles);
}

// Distance of each sample's mirror image to the surface, with the closest point and triangle.
struct Mirrored {
  std::vector<double> distance;
  std::vector<Vec3> image, closest;
  std::vector<int> triangle;
};

Mirrored mirror(const Surface& s, const Plane& plane) {
  Mirrored m;
  const size_t n = s.samples.size();
  m.distance.resize(n);
  m.image.resize(n);
  m.closest.resize(n);
  m.triangle.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const Vec3& p = s.samples[i];
    m.image[i] = p - 2.0 * (plane.n.dot(p) - plane.d) * plane.n;
    m.distance[i] = s.bvh.closest(m.image[i], &m.triangle[i], &m.closest[i]);
  }
  return m;
}

double quantile(std::vector<double> values, double q) {
  const size_t k = std::min(values.size() - 1, static_cast<size_t>(q * static_cast<double>(values.size())));
  std::nth_element(values.begin(), values.begin() + static_cast<long>(k), values.end());
  return values[k];
}

struct MirrorFit {
  Plane plane;
  double residual = 0.0;  // median mirror distance (normalised units)
};

// How the plane's normal may move while it is fitted.
enum class NormalFreedom { kFree, kPerpendicular, kFixed };

// Gauss-Newton on the point-to-plane distances of the mirrored samples to the surface, the
// farthest 40% left out each round (an asymmetric pose: an arm or a leg held differently).
MirrorFit fit_mirror(const Surface& s, Plane plane, NormalFreedom freedom, const Vec3& axis = Vec3::Zero(),
                     int iterations = 20) {
  for (int iteration = 0; iteration < iterations; ++iteration) {
    const Mirrored m = mirror(s, plane);
    const double keep = quantile(m.distance, kTrimmed);
    // Directions the normal may turn in.
    std::vector<Vec3> turns;
    if (freedom == NormalFreedom::kFree) {
      Vec3 u = plane.n.unitOrthogonal();
      turns = {u, plane.n.cross(u)};
    } else if (freedom == NormalFreedom::kPerpendicular) {
      turns = {axis.cross(plane.n).normalized()};
    }
    const int k = static_cast<int>(turns.size()) + 1;  // + the offset
    Eigen::MatrixXd normal_matrix = Eigen::MatrixXd::Zero(k, k);
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(k);
    for (size_t i = 0; i < s.samples.size(); ++i) {
      if (m.distance[i] > keep) continue;
      const Vec3& p = s.samples[i];
      const Vec3& normal = s.normals[static_cast<size_t>(m.triangle[i])];
      const double side = plane.n.dot(p) - plane.d;
      Eigen::VectorXd j(k);
      for (int c = 0; c + 1 < k; ++c)  // image p - 2 (n.p - d) n as n turns by u
        j[c] = normal.dot(
            -2.0 * (turns[static_cast<size_t>(c)].dot(p) * plane.n + side * turns[static_cast<size_t>(c)]));
      j[k - 1] = normal.dot(2.0 * plane.n);  // as d grows
      const double r = normal.dot(m.image[i] - m.closest[i]);
      normal_matrix += j * j.transpose();
      rhs -= j * r;
    }
    normal_matrix.diagonal().array() += 1e-9;
    Eigen::VectorXd step = normal_matrix.ldlt().solve(rhs);
    double turn = 0.0;
    for (int c = 0; c + 1 < k; ++c) turn += step[c] * step[c];
    if (std::sqrt(turn) > 0.1) step.head(k - 1) *= 0.1 / std::sqrt(turn);  // a tenth of a radian at most
    Vec3 n = plane.n;
    for (int c = 0; c + 1 < k; ++c) n += step[c] * turns[static_cast<size_t>(c)];
    plane.n = n.normalized();
    plane.d += step[k - 1];
    if (step.norm() < 1e-7) break;
  }
  const Mirrored m = mirror(s, plane);
  return {plane, quantile(m.distance, 0.5)};
}

// A horizontal slice of the surface: the segments where the triangles cross the level.
struct Slice {
  double gap = std::numeric_limits<double>::infinity();  // nearest approach to the mirror plane
  double lateral = 0.0;                                  // farthest from it
  std::array<double, 2> length{0.0, 0.0};                // per side (-, +)
  std::array<double, 2> ahead_min{kNaN, kNaN}, ahead_max{kNaN, kNaN}, ahead_sum{0.0, 0.0};

  double ahead_mean(int side) const {
    return ahead_sum[static_cast<size_t>(side)] / length[static_cast<size_t>(side)];
  }
  bool split(double gap_limit) const {
    const double lo = std::min(length[0], length[1]), hi = std::max(length[0], length[1]);
    return gap > gap_limit && hi > 0.0 && lo >= 0.3 * hi;
  }
};

Slice slice(const Surface& s, const Vec3& up, double level, const Plane& plane, const Vec3& forward) {
  Slice out;
  for (const Triangle& t : s.triangles) {
    const Vec3* p[3] = {&s.points[static_cast<size_t>(t[0])], &s.points[static_cast<size_t>(t[1])],
                        &s.points[static_cast<size_t>(t[2])]};
    const double h[3] = {up.dot(*p[0]) - level, up.dot(*p[1]) - level, up.dot(*p[2]) - level};
    Vec3 ends[2];
    int found = 0;
    for (int e = 0; e < 3 && found < 2; ++e) {
      const int a = e, b = (e + 1) % 3;
      if ((h[a] >= 0.0) == (h[b] >= 0.0)) continue;
      ends[found++] = *p[a] + h[a] / (h[a] - h[b]) * (*p[b] - *p[a]);
    }
    if (found < 2) continue;
    const double x0 = plane.n.dot(ends[0]) - plane.d, x1 = plane.n.dot(ends[1]) - plane.d;
    out.gap = std::min(out.gap, x0 * x1 <= 0.0 ? 0.0 : std::min(std::abs(x0), std::abs(x1)));
    out.lateral = std::max({out.lateral, std::abs(x0), std::abs(x1)});
    const size_t side = x0 + x1 > 0.0 ? 1 : 0;
    const double length = (ends[1] - ends[0]).norm();
    const double f0 = forward.dot(ends[0]), f1 = forward.dot(ends[1]);
    out.length[side] += length;
    out.ahead_sum[side] += length * 0.5 * (f0 + f1);
    out.ahead_min[side] =
        std::isnan(out.ahead_min[side]) ? std::min(f0, f1) : std::min({out.ahead_min[side], f0, f1});
    out.ahead_max[side] =
        std::isnan(out.ahead_max[side]) ? std::max(f0, f1) : std::max({out.ahead_max[side], f0, f1});
  }
  return out;
}

// Fraction of the slices at 4-40% of the height from the end `up` points away from where the
// surface stands apart on both sides of the mirror plane.
double split_fraction(const Surface& s, const Vec3& up, double height, const Plane& plane) {
  const double bottom = s.lowest(up);
  int split = 0, levels = 0;
  for (double f = 0.04; f < 0.4001; f += 0.02, ++levels)
    split += slice(s, up, bottom + f * height, plane, Vec3::Zero()).split(kLegGap * height);
  return static_cast<double>(split) / levels;
}

struct Axes {
  Vec3 up, forward, right;
  Plane mirror;
  MeshFrame figures;  // the detection's figures; unit and placement not yet set
};

constexpr const char* kNotABody = "the mesh is not a body: ";
std::string not_a_body(const std::string& why) { return kNotABody + why; }

// The body's axes, with the normal of the mirror plane, the vertical or the facing fixed when
// given. Throws std::invalid_argument naming the first check that fails.
Axes detect_axes(const Surface& s, const std::optional<Vec3>& given_up,
                 const std::optional<Vec3>& given_forward) {
  Axes out;
  MeshFrame& fig = out.figures;
  // 1. The mirror plane, from every starting normal the constraints allow.
  std::vector<Vec3> starts;
  NormalFreedom freedom = NormalFreedom::kFree;
  Vec3 axis = Vec3::Zero();
  if (given_up && given_forward) {
    freedom = NormalFreedom::kFixed;
    starts = {given_forward->cross(*given_up).normalized()};
  } else {
    const Eigen::Matrix3d file_axes = Eigen::Matrix3d::Identity();
    Eigen::Matrix3d c = s.covariance;
    if (given_up || given_forward) {
      freedom = NormalFreedom::kPerpendicular;
      axis = given_up ? *given_up : *given_forward;
      const Eigen::Matrix3d flat = Eigen::Matrix3d::Identity() - axis * axis.transpose();
      c = flat * c * flat;
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(c);
    std::vector<Vec3> candidates;
    for (int k = 2; k >= 0; --k) candidates.push_back(eigen.eigenvectors().col(k));
    if (freedom == NormalFreedom::kPerpendicular) {  // the two in-plane axes and their diagonals
      const Vec3 a = eigen.eigenvectors().col(2), b = eigen.eigenvectors().col(1);
      candidates = {a, b, (a + b).normalized(), (a - b).normalized()};
    }
    for (int k = 0; k < 3; ++k) candidates.push_back(file_axes.col(k));
    for (Vec3 c0 : candidates) {
      if (freedom == NormalFreedom::kPerpendicular) c0 -= c0.dot(axis) * axis;
      if (c0.norm() < 0.5) continue;
      c0.normalize();
      bool seen = false;
      for (const Vec3& q : starts) seen = seen || std::abs(q.dot(c0)) > std::cos(3.0 * kDeg);
      if (!seen) starts.push_back(c0);
    }
  }
  // The vertical a plane implies: given, across its normal and the given forward, or the long
  // axis of the surface within it.
  const auto vertical = [&](const Vec3& n) -> Vec3 {
    if (given_up) return *given_up;
    if (given_forward) return n.cross(*given_forward).normalized();
    const Eigen::Matrix3d flat = Eigen::Matrix3d::Identity() - n * n.transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(flat * s.covariance * flat);
    return eigen.eigenvectors().col(2);
  };
  // A few rounds from each start; the plane that mirrors the surface best. Planes that mirror it
  // equally well (a box, a cylinder: shapes with several mirror planes) are told apart by the
  // long axis: a body's mirror plane is the one across which it is slenderest.
  std::vector<MirrorFit> fits;
  std::vector<double> slender;
  for (const Vec3& n : starts) {
    fits.push_back(fit_mirror(s, Plane{n, 0.0}, freedom, axis, 4));
    const Vec3 up = vertical(fits.back().plane.n);
    const double height = s.extent(up);
    slender.push_back(height / s.extent(up.cross(fits.back().plane.n)));
    fits.back().residual /= height;  // now a fraction of the height
  }
  const auto better = [&](size_t i, size_t j) {  // is fit i a better choice than fit j?
    if (std::abs(fits[i].residual - fits[j].residual) <= kSymmetryTie) return slender[i] > slender[j];
    return fits[i].residual < fits[j].residual;
  };
  size_t chosen = 0;
  for (size_t i = 1; i < fits.size(); ++i)
    if (better(i, chosen)) chosen = i;
  MirrorFit best = fit_mirror(s, fits[chosen].plane, freedom, axis);
  double other = kNaN;
  for (const MirrorFit& f : fits)
    if (std::abs(f.plane.n.dot(best.plane.n)) < std::cos(20.0 * kDeg) && !(f.residual >= other))
      other = f.residual;

  // 2. The vertical, snapped to a file axis when close (unless given).
  Vec3 up = vertical(best.plane.n);
  if (!given_up && !given_forward) {
    int k = 0;
    up.cwiseAbs().maxCoeff(&k);
    fig.up_tilt_deg = std::acos(std::min(1.0, std::abs(up[k]))) / kDeg;
    if (fig.up_tilt_deg < kSnapDeg) {
      up = Vec3::Unit(k) * (up[k] < 0.0 ? -1.0 : 1.0);
      Plane start = best.plane;
      start.n = (start.n - start.n.dot(up) * up).normalized();
      best = fit_mirror(s, start, NormalFreedom::kPerpendicular, up);
    }
  }
  out.mirror = best.plane;
  const Vec3 lateral = best.plane.n;
  Vec3 forward = given_forward ? *given_forward : Vec3(up.cross(lateral).normalized());
  const double height = s.extent(up), depth = s.extent(forward);
  fig.symmetry_residual = best.residual / height;
  fig.symmetry_margin = other;
  fig.height_to_depth = height / depth;

  // 3. The checks of a body, and the signs of up and forward.
  if (fig.symmetry_residual > kMaxSymmetryResidual)
    throw std::invalid_argument(not_a_body(text(
        "no mirror symmetry plane (the best leaves its mirror image %.2g%% of its height from the surface)",
        100.0 * fig.symmetry_residual)));
  if (fig.height_to_depth < kMinHeightToDepth)
    throw std::invalid_argument(
        not_a_body(text("its height is only %.2f times its depth (a standing body's is over %.3g)",
                        fig.height_to_depth, kMinHeightToDepth)));
  double bottom_split = split_fraction(s, up, height, best.plane),
         top_split = split_fraction(s, -up, height, best.plane);
  if (!given_up && top_split > bottom_split) {
    up = -up;
    std::swap(bottom_split, top_split);
  }
  fig.leg_split = bottom_split;
  fig.head_split = top_split;
  if (bottom_split < kMinLegSplit)
    throw std::invalid_argument(not_a_body(text(
        "no two legs (its lower part stands apart on both sides of the mirror plane in %.0f%% of the slices)",
        100.0 * bottom_split)));
  if (bottom_split - top_split < kMinSplitContrast)
    throw std::invalid_argument(
        not_a_body(text("both ends split in two (%.0f%% and %.0f%% of the slices), no head end",
                        100.0 * bottom_split, 100.0 * top_split)));

  // Toes: at the soles, the reach ahead of each ankle minus the reach behind it.
  const double bottom = s.lowest(up);
  const Slice ankle = slice(s, up, bottom + 0.10 * height, best.plane, forward);
  std::array<double, 2> reach{0.0, 0.0};
  for (double f : {0.01, 0.02, 0.03}) {
    const Slice sole = slice(s, up, bottom + f * height, best.plane, forward);
    for (int side = 0; side < 2; ++side) {
      const double centre = ankle.ahead_mean(side);
      reach[static_cast<size_t>(side)] += (sole.ahead_max[static_cast<size_t>(side)] - centre +
                                           sole.ahead_min[static_cast<size_t>(side)] - centre) /
                                          (3.0 * height);
    }
  }
  fig.toe_reach = 0.5 * (reach[0] + reach[1]);
  if (!given_forward) {
    if (!(reach[0] * reach[1] > 0.0) || !(std::abs(fig.toe_reach) >= kMinToeReach))
      throw std::invalid_argument(
          text("cannot tell the body's front from its back: its feet point neither way (toe reach %.3g "
               "and %.3g of the height); give the forward axis",
               reach[0], reach[1]));
    if (fig.toe_reach < 0.0) {
      forward = -forward;
      fig.toe_reach = -fig.toe_reach;
    }
  }
  out.up = up;
  out.forward = forward;
  out.right = forward.cross(up);
  return out;
}

// Arm elevation of each side: the direction from the shoulder joint to the far end of the arm
// (the fingertips), in skinstream axes and fractions of the height. The shoulder sits inside the
// top of the shoulders, at the lateral offset of an adult's (biacromial breadth is about 0.23 of
// the stature, the joint centres a little inside); the arm is the surface beyond the hips' and
// the shoulders' half-width and above the crotch.
void measure_arms(const Surface& s, const Axes& axes, MeshFrame& fig) {
  const double height = s.extent(axes.up), bottom = s.lowest(axes.up);
  const double plane_x = axes.mirror.d * axes.right.dot(axes.mirror.n);
  const auto level = [&](double f) {
    return slice(s, axes.up, bottom + f * height, axes.mirror, axes.forward);
  };
  // The crotch: the top of the run of slices, from the shins up, where the legs stand apart.
  double crotch = 0.5;
  if (level(0.10).split(kLegGap * height)) {
    crotch = 0.10;
    while (crotch < 0.7 && level(crotch + 0.01).split(kLegGap * height)) crotch += 0.01;
  }
  const double cut = std::max(kArmCut, 1.25 * level(crotch - 0.05).lateral / height);
  // The top of the shoulders: the highest slice below the head (88%) that reaches beyond the
  // neck's half-width; the joint is kShoulderDepth below it.
  double shoulder_top = 0.83;
  for (double f = 0.88; f > 0.6; f -= 0.01)
    if (level(f).lateral / height > kNeckHalfWidth) {
      shoulder_top = f;
      break;
    }
  const double shoulder_z = shoulder_top - kShoulderDepth;
  const Slice chest = level(shoulder_z);
  const double shoulder_y =
      0.5 * (chest.ahead_sum[0] + chest.ahead_sum[1]) / (chest.length[0] + chest.length[1]) / height;
  for (int side = 0; side < 2; ++side) {
    const double sign = side == 0 ? -1.0 : 1.0;  // left is -X
    const Vec3 shoulder(sign * kShoulderHalfWidth, shoulder_y, shoulder_z);
    double area = 0.0, farthest = 0.0;
    std::vector<std::pair<Vec3, double>> points;
    for (size_t t = 0; t < s.centres.size(); ++t) {
      const Vec3& c = s.centres[t];
      const Vec3 q((axes.right.dot(c) - plane_x) / height, axes.forward.dot(c) / height,
                   (axes.up.dot(c) - bottom) / height);
      if (sign * q.x() <= cut || q.z() <= crotch) continue;
      points.emplace_back(q, s.areas[t]);
      area += s.areas[t];
      farthest = std::max(farthest, (q - shoulder).norm());
    }
    double& elevation = fig.side_arm_elevation_deg[static_cast<size_t>(side)];
    if (area < kMinArmArea * s.area) {
      elevation = kNaN;
      continue;
    }
    // The far end: the surface within 3% of the arm's reach from the farthest point.
    Vec3 tip = Vec3::Zero();
    double tip_area = 0.0;
    for (const auto& [q, a] : points)
      if ((q - shoulder).norm() >= 0.97 * farthest) {
        tip += a * q;
        tip_area += a;
      }
    const Vec3 direction = (tip / tip_area - shoulder).normalized();
    elevation = std::acos(std::clamp(-direction.z(), -1.0, 1.0)) / kDeg;
  }
  fig.arm_elevation_deg = 0.5 * (fig.side_arm_elevation_deg[0] + fig.side_arm_elevation_deg[1]);
}

std::optional<Vec3> checked_axis(const std::optional<Vec3>& axis, const char* name) {
  if (!axis) return axis;
  if (!is_present(*axis) || !(axis->norm() > 0.0))
    throw std::invalid_argument(std::string("the given ") + name + " axis is zero or not finite");
  return axis->normalized();
}

}  // namespace

MeshFrame detect_mesh_frame(std::span<const Vec3> vertices, std::span<const Triangle> triangles,
                            const MeshFrameOptions& options) {
  if (!(options.unit_mm >= 0.0) || !std::isfinite(options.unit_mm))
    throw std::invalid_argument("the given unit must be a positive number of mm (0 to detect it)");
  std::optional<Vec3> up = checked_axis(options.up, "up");
  std::optional<Vec3> forward = checked_axis(options.forward, "forward");
  if (up && forward) {
    const double angle = std::acos(std::clamp(up->dot(*forward), -1.0, 1.0)) / kDeg;
    if (std::abs(angle - 90.0) > 10.0)
      throw std::invalid_argument(
          text("the given up and forward axes are %.0f degrees apart, not perpendicular", angle));
    forward = (*forward - forward->dot(*up) * *up).normalized();
  }
  const Surface s(vertices, triangles);

  Axes axes;
  if (!up && !forward) {
    axes = detect_axes(s, up, forward);
  } else {
    try {
      axes = detect_axes(s, up, forward);
    } catch (const std::invalid_argument& constrained) {
      // Say what the body looks like without the override, when it looks like one.
      Axes free;
      try {
        free = detect_axes(s, std::nullopt, std::nullopt);
      } catch (const std::invalid_argument&) {
        throw constrained;
      }
      std::string given;
      if (options.up) given = "up " + vec_text(*options.up);
      if (options.forward)
        given += (given.empty() ? "forward " : " and forward ") + vec_text(*options.forward);
      std::string why = constrained.what();
      if (why.rfind(kNotABody, 0) == 0) why.erase(0, std::string(kNotABody).size());
      throw std::invalid_argument("the given " + given + " does not fit the body, which stands up along " +
                                  vec_text(free.up) + " and faces " + vec_text(free.forward) + "; with it, " +
                                  why);
    }
  }
  MeshFrame frame = axes.figures;
  measure_arms(s, axes, frame);

  // The unit: the one that makes the height a human's.
  const double height = s.extent(axes.up) * s.scale;  // file units
  if (options.unit_mm > 0.0) {
    const double mm = height * options.unit_mm;
    if (mm < kMinHeightMm || mm > kMaxHeightMm)
      throw std::invalid_argument(
          unit_text(options.unit_mm) +
          text(" the mesh would be %.3g m tall (a body is %.3g to %.3g m); check the unit", mm / 1000.0,
               kMinHeightMm / 1000.0, kMaxHeightMm / 1000.0));
    frame.unit_mm = options.unit_mm;
  } else {
    frame.unit_mm = 0.0;
    for (double unit : {1.0, 10.0, 100.0, 1000.0})
      if (height * unit >= kMinHeightMm && height * unit <= kMaxHeightMm) frame.unit_mm = unit;
    if (frame.unit_mm == 0.0)
      throw std::invalid_argument(
          text("the mesh is %.4g units tall: no unit of mm, cm, dm or m makes that a body's "
               "height (%.3g to %.3g m); give the unit",
               height, kMinHeightMm / 1000.0, kMaxHeightMm / 1000.0));
  }
  frame.height_mm = height * frame.unit_mm;

  // Rows: the file directions of skinstream's +X (right), +Y (forward) and +Z (up).
  frame.rotation.row(0) = axes.right.transpose();
  frame.rotation.row(1) = axes.forward.transpose();
  frame.rotation.row(2) = axes.up.transpose();
  // Placement, in file units about the file origin: the mirror plane's offset along right, the
  // centroid along forward, the lowest point along up.
  const double plane_x = axes.right.dot(s.centroid) + s.scale * axes.mirror.d * axes.right.dot(axes.mirror.n);
  const double centre_y = axes.forward.dot(s.centroid);
  const double ground = axes.up.dot(s.centroid) + s.scale * s.lowest(axes.up);
  frame.translation = -frame.unit_mm * Vec3(plane_x, centre_y, ground);
  return frame;
}

std::vector<Vec3> to_skinstream_axes(const MeshFrame& frame, std::span<const Vec3> vertices) {
  std::vector<Vec3> out;
  out.reserve(vertices.size());
  for (const Vec3& p : vertices) out.push_back(frame.unit_mm * (frame.rotation * p) + frame.translation);
  return out;
}

}  // namespace skinstream
