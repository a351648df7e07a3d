#pragma once
// A small synthetic "limb" for core tests: markers on a grid over a cylinder that moves
// rigidly through space while it bulges and twists (two deformation modes), with known truth.
#include <cmath>
#include <string>
#include <vector>

#include "core/capture.h"

namespace skinstream::test {

struct LimbOptions {
  int around = 8;
  int along = 7;
  double radius = 60.0;     // mm
  double length = 300.0;    // mm
  double bulge = 0.15;      // relative radius change
  double twist = 0.3;       // radians end to end
  int frames = 600;
  double rate = 120.0;
};

inline Vec3 limb_point(const LimbOptions& o, int a, int l, int frame) {
  const double t = frame / o.rate;
  const double z = o.length * l / (o.along - 1);
  const double profile = std::sin(M_PI * z / o.length);
  const double r = o.radius * (1.0 + o.bulge * std::sin(2.0 * M_PI * 0.7 * t) * profile);
  const double angle = 2.0 * M_PI * a / o.around + o.twist * std::sin(2.0 * M_PI * 0.4 * t) * z / o.length;
  const Vec3 local(r * std::cos(angle), r * std::sin(angle), z);
  // Rigid motion: rotation about a tilted axis and a translation loop.
  const double yaw = 0.8 * std::sin(2.0 * M_PI * 0.25 * t), pitch = 0.5 * std::sin(2.0 * M_PI * 0.33 * t);
  const double cy = std::cos(yaw), sy = std::sin(yaw), cp = std::cos(pitch), sp = std::sin(pitch);
  const Vec3 p1(cy * local.x() - sy * local.y(), sy * local.x() + cy * local.y(), local.z());
  const Vec3 p2(p1.x(), cp * p1.y() - sp * p1.z(), sp * p1.y() + cp * p1.z());
  return p2 + Vec3(400.0 * std::sin(2.0 * M_PI * 0.2 * t), 200.0 * t, 1000.0);
}

inline Capture make_limb_capture(const LimbOptions& o = {}) {
  std::vector<std::string> labels;
  for (int l = 0; l < o.along; ++l)
    for (int a = 0; a < o.around; ++a) labels.push_back("limb_" + std::to_string(l) + "_" + std::to_string(a));
  Capture c(labels, o.frames, o.rate);
  for (int f = 0; f < o.frames; ++f)
    for (int l = 0; l < o.along; ++l)
      for (int a = 0; a < o.around; ++a) c.at(f, l * o.around + a) = limb_point(o, a, l, f);
  return c;
}

}  // namespace skinstream::test
