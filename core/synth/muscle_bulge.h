#pragma once
// Muscles that bulge when their joint flexes: the skin over the muscle belly moves out along
// its normal by an amount that grows with the flexion of a driving joint (a muscle shortens and
// thickens) and with voluntary effort (isometric tension, as when a bodybuilder poses).
// Biceps and forearm flexors follow the elbow, quadriceps and hamstrings the knee, the calf the
// ankle's plantarflexion, deltoid and pectoral the elevation of the arm, the abdominals the
// forward bend of the spine, the gluteus the extension of the hip. Driver angles are measured
// from the rest pose, so the rest pose carries no bulge (the rest mesh is the relaxed shape).
#include <string>
#include <vector>

#include "core/body/anatomy.h"
#include "core/synth/body_region.h"

namespace skinstream::synth {

struct Muscle {
  std::string name;  // e.g. "biceps_L"
  Region region;
  // Driver: the sum over driver_bones of the rotation angle of their local rotation about
  // driver_axis (kAboutAxis), or of the angle their local rotation turns swing_dir by (kSwing).
  enum class Driver { kAboutAxis, kSwing } driver = Driver::kAboutAxis;
  std::vector<int> driver_bones;
  Vec3 driver_axis = Vec3::UnitX();  // kAboutAxis: unit axis; kSwing: the rest direction turned
  double zero_angle = 0.0;           // radians of driver angle with no bulge
  double full_angle = 1.0;           // radians beyond zero_angle for the full bulge
  double amplitude_mm = 0.0;         // bulge at full flexion (with no effort: 60% of it)
  double effort_mm = 0.0;            // extra bulge at full effort
};

// The muscles of both sides of a MakeHuman-style body. Bones that are absent are skipped.
std::vector<Muscle> standard_muscles(const Body& body, const Anatomy& anatomy);

double muscle_activation(const Muscle& muscle, const Pose& pose);               // 0..1
double muscle_bulge_mm(const Muscle& muscle, const Pose& pose, double effort);  // outward, mm

}  // namespace skinstream::synth
