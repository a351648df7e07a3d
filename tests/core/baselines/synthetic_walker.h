#pragma once
// A synthetic walker for the gap-filler tests: the 41 CMU / Plug-in Gait markers on a kinematic
// chain of rigid segments that walks forward with a cadence that drifts, so marker trajectories
// are long, curved and intercorrelated like real gait, with known truth. Millimetres, Z up,
// walking towards +Y, left on -X.
#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "core/capture.h"

namespace skinstream::test {

struct WalkerOptions {
  int frames = 3600;
  double rate = 120.0;
  double noise_mm = 0.0;  // deterministic pseudo-random jitter per sample, uniform in +-noise_mm
};

namespace walker_detail {

using Rotation = Eigen::Matrix3d;
inline Rotation about_x(double a) { return Eigen::AngleAxisd(a, Vec3::UnitX()).toRotationMatrix(); }
inline Rotation about_y(double a) { return Eigen::AngleAxisd(a, Vec3::UnitY()).toRotationMatrix(); }
inline Rotation about_z(double a) { return Eigen::AngleAxisd(a, Vec3::UnitZ()).toRotationMatrix(); }

// A segment's pose in the world.
struct Pose {
  Rotation rotation = Rotation::Identity();
  Vec3 origin = Vec3::Zero();
  Vec3 apply(const Vec3& local) const { return origin + rotation * local; }
  Pose child(const Vec3& joint, const Rotation& turn) const { return {rotation * turn, apply(joint)}; }
};

inline double jitter(uint64_t key) {  // splitmix64 -> [-1, 1)
  key += 0x9e3779b97f4a7c15ULL;
  key = (key ^ (key >> 30)) * 0xbf58476d1ce4e5b9ULL;
  key = (key ^ (key >> 27)) * 0x94d049bb133111ebULL;
  key ^= key >> 31;
  return static_cast<double>(key >> 11) * 0x1.0p-52 - 1.0;
}

}  // namespace walker_detail

inline std::vector<std::string> walker_labels() {
  return {"LFWT", "RFWT", "LBWT", "RBWT", "LTHI", "LKNE", "LSHN", "LANK", "LHEE", "LMT5", "LTOE",
          "RTHI", "RKNE", "RSHN", "RANK", "RHEE", "RMT5", "RTOE", "CLAV", "STRN", "C7",   "T10",
          "RBAC", "LFHD", "RFHD", "LBHD", "RBHD", "LSHO", "LUPA", "LELB", "LFRM", "LWRA", "LWRB",
          "LFIN", "RSHO", "RUPA", "RELB", "RFRM", "RWRA", "RWRB", "RFIN"};
}

inline Capture make_walker_capture(const WalkerOptions& options = {}) {
  using namespace walker_detail;
  Capture capture(walker_labels(), options.frames, options.rate);
  double phase = 0.0;
  for (int f = 0; f < options.frames; ++f) {
    const double t = f / options.rate;
    const double cadence = 0.9 + 0.2 * std::sin(2.0 * M_PI * 0.05 * t);  // strides per second
    if (f > 0) phase += 2.0 * M_PI * cadence / options.rate;
    const double arm_amplitude = 0.35 + 0.15 * std::sin(2.0 * M_PI * 0.07 * t);
    std::vector<Vec3> at;

    const Pose pelvis{about_z(0.12 * std::sin(phase)),
                      Vec3(30.0 * std::sin(phase), 1100.0 * t, 950.0 + 20.0 * std::sin(2.0 * phase))};
    for (const Vec3& m : {Vec3(-120, 80, 0), Vec3(120, 80, 0), Vec3(-80, -100, 20), Vec3(80, -100, 20)})
      at.push_back(pelvis.apply(m));

    for (int side = 0; side < 2; ++side) {  // left, right legs
      const double s = side == 0 ? -1.0 : 1.0, offset = side == 0 ? 0.0 : M_PI;
      const Pose thigh =
          pelvis.child(Vec3(s * 90, 0, -80), about_x(0.45 * std::sin(phase + offset)) * about_y(s * 0.05));
      const Pose shank =
          thigh.child(Vec3(0, 0, -430), about_x(-0.35 * (1.0 - std::cos(phase + offset - 0.6))));
      const Pose foot = shank.child(Vec3(0, 0, -410), about_x(0.25 * std::sin(phase + offset - 1.2)));
      at.push_back(thigh.apply(Vec3(s * 60, 30, -200)));  // THI
      at.push_back(thigh.apply(Vec3(s * 50, 0, -420)));   // KNE
      at.push_back(shank.apply(Vec3(s * 50, 40, -200)));  // SHN
      at.push_back(shank.apply(Vec3(s * 45, 0, -400)));   // ANK
      at.push_back(foot.apply(Vec3(0, -50, -60)));        // HEE
      at.push_back(foot.apply(Vec3(s * 40, 100, -55)));   // MT5
      at.push_back(foot.apply(Vec3(0, 140, -60)));        // TOE
    }

    const Pose torso =
        pelvis.child(Vec3(0, 0, 0), about_z(-0.18 * std::sin(phase)) * about_x(0.05 * std::sin(2.0 * phase)));
    for (const Vec3& m :
         {Vec3(0, 90, 450), Vec3(0, 110, 300), Vec3(0, -80, 520), Vec3(0, -110, 300), Vec3(60, -110, 380)})
      at.push_back(torso.apply(m));  // CLAV STRN C7 T10 RBAC
    const Pose head = torso.child(Vec3(0, 0, 560), about_x(0.1 * std::sin(2.0 * M_PI * 0.13 * t)));
    for (const Vec3& m : {Vec3(-60, 80, 120), Vec3(60, 80, 120), Vec3(-60, -60, 130), Vec3(60, -60, 130)})
      at.push_back(head.apply(m));  // LFHD RFHD LBHD RBHD

    for (int side = 0; side < 2; ++side) {  // left, right arms swing against their legs
      const double s = side == 0 ? -1.0 : 1.0, offset = side == 0 ? M_PI : 0.0;
      at.push_back(torso.apply(Vec3(s * 180, 0, 480)));  // SHO
      const Pose upper = torso.child(Vec3(s * 190, 0, 460),
                                     about_x(arm_amplitude * std::sin(phase + offset)) * about_y(s * -0.12));
      const Pose fore = upper.child(Vec3(0, 0, -300), about_x(0.5 + 0.3 * std::sin(phase + offset + 0.4)));
      at.push_back(upper.apply(Vec3(s * 40, 0, -150)));    // UPA
      at.push_back(upper.apply(Vec3(0, -40, -290)));       // ELB
      at.push_back(fore.apply(Vec3(s * 35, 10, -120)));    // FRM
      at.push_back(fore.apply(Vec3(s * 20, 30, -250)));    // WRA
      at.push_back(fore.apply(Vec3(s * -20, -30, -250)));  // WRB
      at.push_back(fore.apply(Vec3(0, 10, -330)));         // FIN
    }

    for (int p = 0; p < capture.point_count(); ++p) {
      Vec3 position = at[static_cast<size_t>(p)];
      if (options.noise_mm > 0.0)
        for (int k = 0; k < 3; ++k)
          position(k) += options.noise_mm * jitter((static_cast<uint64_t>(f) * 64 + p) * 4 + k);
      capture.at(f, p) = position;
    }
  }
  return capture;
}

}  // namespace skinstream::test
