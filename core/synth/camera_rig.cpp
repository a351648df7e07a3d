#include "core/synth/camera_rig.h"

#include <cmath>

namespace skinstream::synth {

CameraRig CameraRig::stage12(const Vec3& centre, double radius, double high_mm, double aim_high_mm,
                             double low_mm, double aim_low_mm) {
  CameraRig rig;
  for (int i = 0; i < 10; ++i) {
    const double a = 2.0 * M_PI * (i + 0.5) / 10.0;
    Camera c;
    c.position = centre + Vec3(radius * std::cos(a), radius * std::sin(a), high_mm);
    c.forward = (centre + Vec3(0, 0, aim_high_mm) - c.position).normalized();
    c.half_fov_deg = 40.0;
    rig.cameras.push_back(c);
  }
  for (double a : {0.25 * M_PI, 1.25 * M_PI}) {  // front-left and back-right of a subject facing +Y
    Camera c;
    c.position = centre + Vec3(0.85 * radius * std::cos(a + 0.5 * M_PI),
                               0.85 * radius * std::sin(a + 0.5 * M_PI), low_mm);
    c.forward = (centre + Vec3(0, 0, aim_low_mm) - c.position).normalized();
    c.half_fov_deg = 40.0;
    rig.cameras.push_back(c);
  }
  return rig;
}

int cameras_seeing(const CameraRig& rig, const TriangleBvh& body, const Vec3& p, const Vec3& n,
                   const VisibilityRule& rule, Random* random) {
  const double cos_view = std::cos(rule.max_view_angle_deg * M_PI / 180.0);
  const double cos_sure = std::cos(std::min(rule.grazing_start_deg, rule.max_view_angle_deg) * M_PI / 180.0);
  int seen = 0;
  for (const Camera& c : rig.cameras) {
    const Vec3 to_cam = c.position - p;
    const double dist = to_cam.norm();
    if (dist <= 0.0) continue;
    const Vec3 dir = to_cam / dist;
    const double facing = n.dot(dir);
    if (facing < cos_view) continue;
    if ((-dir).dot(c.forward) < std::cos(c.half_fov_deg * M_PI / 180.0)) continue;
    if (body.segment_blocked(p, c.position, rule.skip_mm)) continue;
    if (random) {
      const double u_grazing = random->uniform(), u_drop = random->uniform();
      if (facing < cos_sure && u_grazing > (facing - cos_view) / (cos_sure - cos_view)) continue;
      if (u_drop < rule.camera_dropout) continue;
    }
    ++seen;
  }
  return seen;
}

}  // namespace skinstream::synth
