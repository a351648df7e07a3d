#pragma once
// Raw training capture -> immutable SubjectModel (section 4.1-4.3), offline and once per subject.

#include <array>
#include <string>
#include <vector>

#include "core/capture.h"
#include "core/offline/marker_pca_trainer.h"
#include "core/offline/region_pca_trainer.h"
#include "core/offline/marker_surface_builder.h"
#include "core/subject_model.h"

namespace skinstream {

struct SubjectBuildOptions {
  int reference_frame = -1;  // frame index; -1 chooses one automatically
  PcaTrainingOptions pca;
  RegionPcaOptions region_pca;
  bool regions = true;  // false: no regional models (the filler then has none of their opinions)
  MarkerSurfaceOptions surface;
  int anchors = 8;           // markers a marker is held to when nothing else is known
  FillParameters parameters;
};

struct SubjectBuildReport {
  int reference_frame = -1;
  int markers = 0;
  int triangles = 0;
  int markers_given_extra_neighbours = 0;
  double mean_ring_size = 0.0;
  double mean_pca_components = 0.0;
  int min_training_frames = 0;
  std::vector<std::string> markers_never_complete;  // PCA fell back to the reference shape
};

// The frame (index) where every listed marker is present and markers are most spread out
// (largest mean nearest-neighbour distance: limbs away from the body, nothing confusable);
// -1 when no frame has them all.
int choose_reference_frame(const Capture& capture, const std::vector<int>& markers);

// Uses the labelled channels of `training`. `triangles`, when given, is the user's marker
// surface (indices into the labelled markers). Throws std::invalid_argument on unusable input.
SubjectModel build_subject(const Capture& training, const SubjectBuildOptions& options,
                           const std::vector<std::array<int, 3>>* triangles = nullptr,
                           SubjectBuildReport* out_report = nullptr);

}  // namespace skinstream
