#pragma once
// The synthetic dense-marker capture generator (what Park & Hodgins recorded with 350 markers
// and 12 cameras, made from a skinned body): poses the body with a procedural motion at 120 Hz,
// deforms its skin beyond skinning (muscle bulges, breathing, soft-tissue jiggle), carries
// markers on the deforming surface, decides per frame which markers the camera stage
// reconstructs, and breaks the trajectories as an optical system does. Returns the broken
// capture, the truth, the per-frame truth mesh on demand and the counts of Park & Hodgins'
// Table 1. Everything follows from the seed.
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/capture.h"
#include "core/synth/camera_rig.h"
#include "core/synth/deformation.h"
#include "core/synth/marker_layout.h"
#include "core/synth/trajectory_breaker.h"

namespace skinstream::synth {

struct SynthOptions {
  std::string motion = "rom";  // see motion.h
  double seconds = 5.0;
  double rate_hz = 120.0;
  uint64_t seed = 1;
  int markers = 350;
  bool subdivided = false;        // markers and truth mesh on the once-subdivided body
  double marker_offset_mm = 4.0;  // marker centre above the skin along the normal
  bool deform = true;             // false: skinning only (no bulge, breathing or jiggle)
  DeformOptions deformation;
  LayoutOptions layout;  // layout.count is replaced by `markers`
  BreakOptions breaking;
  VisibilityRule visibility;
  std::optional<CameraRig> cameras;  // default: CameraRig::stage12()
  int bvh_rebuild_every = 30;        // frames between full rebuilds (refit in between)
};

struct SynthCounts {
  int markers = 0;
  int frames = 0;
  int trajectories_before_merging = 0;  // partial trajectories delivered, ghosts included
  int labelled_fragments = 0;
  int unlabelled_fragments = 0;
  int wrong_label_fragments = 0;
  int ghost_trajectories = 0;
  int ghost_points = 0;          // ghost samples
  long holes = 0;                // marker-frames delivered in no channel
  int gaps = 0;                  // runs of such marker-frames
  double occluded_fraction = 0;  // marker-frames not reconstructed by the cameras
  double missing_fraction = 0;   // of the labelled channels' samples in the broken capture
};

class SynthCapture {
 public:
  Capture capture;                  // what the capture system delivers (mm, NaN = missing)
  Capture truth;                    // every labelled marker, every frame, no noise
  std::vector<int> source;          // per sample of `capture`: true marker, -1 ghost, -2 none
  std::vector<uint8_t> visible;     // frame-major (frame * markers + marker): reconstructed by >= 2 cameras
  std::vector<MarkerSite> markers;  // on the chosen mesh (triangle + barycentric), truth order
  std::vector<std::vector<int>> neighbours;  // markers near each marker on the skin
  SynthCounts counts;

  int frame_count() const { return truth.frame_count; }
  int mesh_vertex_count() const;
  const std::vector<Triangle>& mesh_triangles() const;
  const std::vector<Face>& mesh_faces() const;
  // Truth mesh vertex positions (mm) of the chosen mesh at a frame; skin_only leaves out the
  // bulges, breathing and jiggle. Throws std::out_of_range for a bad frame.
  std::vector<Vec3> pose_mesh(int frame, bool skin_only = false) const;
  const Pose& pose(int frame) const;

 private:
  friend SynthCapture generate(const Body& body, const SynthOptions& options);
  struct Scene;
  std::shared_ptr<const Scene> scene_;
};

// Throws std::invalid_argument for an invalid body or options (unknown motion, seconds or rate
// not positive, fewer markers than the extras, negative offset or noise...).
SynthCapture generate(const Body& body, const SynthOptions& options);

// Counts as JSON-friendly key/value pairs, in a fixed order.
std::vector<std::pair<std::string, double>> counts_table(const SynthCounts& counts);

}  // namespace skinstream::synth
