#pragma once
// An articulated limb for the segmentation and weight tests: `segments` rigid cylinders in a
// chain along z, each bending at its joint about its own axis with its own rhythm while the
// whole chain moves. Markers sit on rings around each segment (none on a joint); the marker
// surface joins consecutive rings, so the triangles between the last ring of a segment and the
// first of the next span the joint.
#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <vector>

#include "core/absolute_orientation.h"
#include "core/capture.h"

namespace skinstream::test {

struct ArticulatedLimb {
  std::vector<Vec3> reference;                // marker positions, straight limb (mm)
  std::vector<Vec3> positions;                // frames x markers, frame-major
  std::vector<std::array<int, 3>> triangles;  // marker surface
  std::vector<int> segment;                   // per marker
  int around = 8, rings_per_segment = 4;
  int marker(int ring, int a) const { return ring * around + a; }
};

inline ArticulatedLimb make_articulated_limb(int segments, int frames, double segment_length = 200.0, double radius = 40.0) {
  ArticulatedLimb limb;
  const int rings = segments * limb.rings_per_segment;
  auto pose = [&](double t, int seg, const Vec3& local) {
    // Root motion, then each joint k bends about an axis turning with k.
    Eigen::Isometry3d x = Eigen::Isometry3d::Identity();
    x.translate(Vec3(300.0 * std::sin(0.9 * t), 100.0 * t, 900.0));
    x.rotate(Eigen::AngleAxisd(0.6 * std::sin(0.7 * t), Vec3::UnitY()));
    for (int k = 1; k <= seg; ++k) {
      x.translate(Vec3(0, 0, segment_length));
      const Vec3 axis(std::cos(1.1 * k), std::sin(1.1 * k), 0.0);
      x.rotate(Eigen::AngleAxisd(0.9 * std::sin((1.3 + 0.8 * k) * t + k), axis));
    }
    return Vec3(x * local);
  };
  // Each marker in its segment's coordinates; the reference is the straight limb.
  std::vector<Vec3> local;
  for (int r = 0; r < rings; ++r) {
    const int seg = r / limb.rings_per_segment;
    const double z = segment_length * ((r % limb.rings_per_segment) + 0.5) / limb.rings_per_segment;
    for (int a = 0; a < limb.around; ++a) {
      const double angle = 2.0 * M_PI * a / limb.around;
      local.emplace_back(radius * std::cos(angle), radius * std::sin(angle), z);
      limb.reference.push_back(local.back() + Vec3(0, 0, seg * segment_length));
      limb.segment.push_back(seg);
    }
  }
  for (int f = 0; f < frames; ++f)
    for (size_t i = 0; i < local.size(); ++i) limb.positions.push_back(pose(f / 60.0, limb.segment[i], local[i]));
  for (int r = 0; r + 1 < rings; ++r)
    for (int a = 0; a < limb.around; ++a) {
      const int a1 = (a + 1) % limb.around;
      limb.triangles.push_back({limb.marker(r, a), limb.marker(r, a1), limb.marker(r + 1, a1)});
      limb.triangles.push_back({limb.marker(r, a), limb.marker(r + 1, a1), limb.marker(r + 1, a)});
    }
  return limb;
}

// Moves `marker` from where its own segment carries it toward where the segment of `ring` (a
// ring of another segment) would carry it rigidly, by `share` of the way (1: wholly with it).
inline void move_with_ring(ArticulatedLimb& limb, int marker, int ring, int frames, double share) {
  const size_t m = limb.reference.size();
  for (int f = 0; f < frames; ++f) {
    std::vector<Vec3> src, dst;
    for (int a = 0; a < limb.around; ++a) {
      src.push_back(limb.reference[limb.marker(ring, a)]);
      dst.push_back(limb.positions[f * m + limb.marker(ring, a)]);
    }
    RigidTransform other;
    fit_rigid(src, dst, other);
    Vec3& p = limb.positions[f * m + marker];
    p = (1.0 - share) * p + share * other.apply(limb.reference[marker]);
  }
}

// Halfway: a marker that belongs to both segments.
inline void move_halfway(ArticulatedLimb& limb, int marker, int ring, int frames) {
  move_with_ring(limb, marker, ring, frames, 0.5);
}

}  // namespace skinstream::test
