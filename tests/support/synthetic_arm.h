#pragma once
// A small synthetic arm for core tests: an upper arm and a forearm (the hand rigid with it) joined
// at an elbow that flexes by `elbow(frame)` radians about the elbow's axis, the whole arm moving
// rigidly through space. Three markers along one side (UPA on the upper arm, FRM on the forearm,
// FIN on the hand) lie nearly on one line while the elbow is straight, as a finger, a forearm and
// an upper arm marker do; WRA and WRB sit at the wrist. Millimetres, known truth, a small seeded
// jitter per sample (the capture system's noise).
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "core/capture.h"
#include "core/synth/random.h"

namespace skinstream::test {

enum ArmMarker { kUPA, kU1, kU2, kFRM, kF1, kF2, kWRA, kWRB, kFIN, kArmMarkers };

inline std::vector<std::string> arm_labels() { return {"UPA", "U1", "U2", "FRM", "F1", "F2", "WRA", "WRB", "FIN"}; }

struct ArmOptions {
  int frames = 600;
  double rate = 120.0;
  double noise_mm = 0.3;  // uniform in +-noise_mm per coordinate
  uint64_t seed = 1;
  std::function<double(int frame)> elbow;  // flexion in radians; empty: straight
};

// Each marker in its segment's frame: the upper arm's from the shoulder, the forearm's from the
// elbow, 300 mm below the shoulder (arm hanging along -z).
inline Vec3 arm_local_position(int marker) {
  static const Vec3 positions[kArmMarkers] = {
      {45, 0, -150},   // UPA: upper arm, on the line
      {0, 45, -150},   // U1
      {-45, 0, -150},  // U2
      {40, 2, -120},   // FRM: forearm, on the line
      {0, 40, -120},   // F1
      {-40, 0, -120},  // F2
      {45, -5, -255},  // WRA: wrist, by the line
      {28, 20, -250},  // WRB: wrist, 31 mm from WRA
      {35, -2, -330},  // FIN: hand, on the line
  };
  return positions[marker];
}

inline bool on_forearm(int marker) { return marker >= kFRM; }

inline Capture make_arm_capture(const ArmOptions& o) {
  Capture c(arm_labels(), o.frames, o.rate);
  synth::Random noise(o.seed);
  for (int f = 0; f < o.frames; ++f) {
    const double t = f / o.rate;
    const Eigen::Matrix3d whole = (Eigen::AngleAxisd(0.8 * std::sin(2.0 * M_PI * 0.25 * t), Vec3::UnitZ()) *
                                   Eigen::AngleAxisd(0.5 * std::sin(2.0 * M_PI * 0.33 * t), Vec3::UnitX()))
                                      .toRotationMatrix();
    const Vec3 shoulder(400.0 * std::sin(2.0 * M_PI * 0.2 * t), 200.0 * t, 1400.0);
    const Eigen::Matrix3d flex = Eigen::AngleAxisd(o.elbow ? o.elbow(f) : 0.0, Vec3::UnitX()).toRotationMatrix();
    for (int m = 0; m < kArmMarkers; ++m) {
      const Vec3 local = arm_local_position(m);
      const Vec3 in_upper = on_forearm(m) ? Vec3(0, 0, -300) + flex * local : local;
      Vec3 p = shoulder + whole * in_upper;
      for (int k = 0; k < 3; ++k) p(k) += noise.uniform(-o.noise_mm, o.noise_mm);  // drawn in order, reproducible
      c.at(f, m) = p;
    }
  }
  return c;
}

// The marker surface: WRB's one-ring is FIN, FRM and UPA (nearly collinear with the elbow
// straight, across the elbow) and WRA; WRA's is WRB, FIN and F1, so with WRA and WRB both missing
// WRA's rigid estimate rests on WRB's.
inline std::vector<std::array<int, 3>> arm_triangles() {
  return {{kWRB, kFIN, kFRM}, {kWRB, kFRM, kUPA}, {kWRA, kWRB, kFIN}, {kWRA, kFIN, kF1},
          {kUPA, kU1, kFRM},  {kU1, kF1, kFRM},   {kU1, kU2, kF1},    {kU2, kF2, kF1},
          {kF1, kF2, kFIN}};
}

}  // namespace skinstream::test
