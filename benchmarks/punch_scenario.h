#pragma once
// The benchmarks' subject and take: the subdivided MakeHuman body (~53,500 vertices) trained on
// the generator's 10 s range-of-motion take (seed 1, ~350 markers in ~17 parts), and the markers
// of its 5 s punching take. Built once per program (about a minute).

#include <vector>

#include "core/capture.h"
#include "core/deform/deformation_model.h"
#include "core/subject_model.h"

namespace skinstream {

struct Scenario {
  SubjectModel subject;
  DeformationModel model;
  std::vector<std::vector<Vec3>> frames;  // subject order
};

const Scenario& scenario();

}  // namespace skinstream
