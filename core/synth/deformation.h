#pragma once
// Skin that deforms beyond skinning: linear blend skinning plus three kinds of effects, each a
// region of the surface with a per-frame value -
//   muscle bulges (muscle_bulge.h) and breathing (breathing.h): mm along the posed normal;
//   soft-tissue jiggle (soft_tissue_jiggle.h): an offset vector in world axes.
// DeformationModel holds the effects and computes their values over a take (jiggle needs the
// whole sequence); DeformedSurface applies them to one mesh (the body or its subdivision).
#include <string>
#include <vector>

#include "core/body/anatomy.h"
#include "core/synth/body_region.h"
#include "core/synth/breathing.h"
#include "core/synth/muscle_bulge.h"
#include "core/synth/soft_tissue_jiggle.h"

namespace skinstream::synth {

struct DeformOptions {
  double muscle_scale = 1.0;  // multiplies every muscle amplitude; 0 disables
  double breath_scale = 1.0;
  double jiggle_scale = 1.0;
};

struct EffectValue {
  double normal_mm = 0.0;         // along the posed normal
  Vec3 offset_mm = Vec3::Zero();  // world axes
};
using EffectFrame = std::vector<EffectValue>;  // one per effect

class DeformationModel {
 public:
  DeformationModel() = default;
  DeformationModel(const Body& body, const Anatomy& anatomy, const DeformOptions& options);

  int effect_count() const { return static_cast<int>(regions_.size()); }
  const std::vector<std::string>& effect_names() const { return names_; }
  const std::vector<Region>& regions() const { return regions_; }
  const std::vector<Muscle>& muscles() const { return muscles_; }

  // Effect values of every frame of a take sampled at rate_hz: poses (for muscle drivers),
  // their bone transforms (for jiggle anchors), breath and effort per frame.
  std::vector<EffectFrame> drive(const std::vector<Pose>& poses, const std::vector<BoneTransforms>& bones,
                                 const std::vector<double>& breath, const std::vector<double>& effort,
                                 double rate_hz) const;

 private:
  DeformOptions options_;
  std::vector<std::string> names_;
  std::vector<Region> regions_;  // effect order: muscles, breathing parts, jiggle regions
  std::vector<Muscle> muscles_;
  std::vector<BreathingPart> breathing_;
  std::vector<JiggleRegion> jiggle_;
};

// One mesh with the effects' footprints, posed per frame.
class DeformedSurface {
 public:
  DeformedSurface() = default;
  DeformedSurface(std::vector<Vec3> rest, const std::vector<Face>& faces, SkinWeights weights,
                  const DeformationModel& model);

  int vertex_count() const { return static_cast<int>(rest_.size()); }
  const std::vector<Vec3>& rest() const { return rest_; }
  const std::vector<Vec3>& rest_normals() const { return rest_normals_; }
  const std::vector<Triangle>& triangles() const { return triangles_; }
  const std::vector<int>& triangle_face() const { return triangle_face_; }
  const SkinWeights& weights() const { return weights_; }

  // Posed position of vertex v; `skin_only` skips the effects.
  Vec3 vertex(int v, const BoneTransforms& bones, const EffectFrame& effects, bool skin_only = false) const;
  void pose(const BoneTransforms& bones, const EffectFrame& effects, std::vector<Vec3>& out,
            bool skin_only = false) const;
  // Largest effect displacement (mm) of vertex v at this frame: how far it is from skinning.
  double effect_magnitude(int v, const BoneTransforms& bones, const EffectFrame& effects) const;

 private:
  std::vector<Vec3> rest_;
  std::vector<Vec3> rest_normals_;
  std::vector<Triangle> triangles_;
  std::vector<int> triangle_face_;
  SkinWeights weights_;
  // Effects touching each vertex (compressed rows).
  std::vector<int> effect_offsets_{0};
  std::vector<int> effect_ids_;
  std::vector<double> effect_weights_;
};

}  // namespace skinstream::synth
