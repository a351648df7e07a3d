#include "core/synth/deformation.h"

#include <stdexcept>

#include "core/body/skinning.h"

namespace skinstream::synth {

DeformationModel::DeformationModel(const Body& body, const Anatomy& anatomy, const DeformOptions& options)
    : options_(options),
      muscles_(standard_muscles(body, anatomy)),
      breathing_(standard_breathing(body, anatomy)),
      jiggle_(standard_jiggle(body, anatomy)) {
  for (const Muscle& m : muscles_) {
    names_.push_back("muscle:" + m.name);
    regions_.push_back(m.region);
  }
  for (const BreathingPart& b : breathing_) {
    names_.push_back("breath:" + b.name);
    regions_.push_back(b.region);
  }
  for (const JiggleRegion& j : jiggle_) {
    names_.push_back("jiggle:" + j.name);
    regions_.push_back(j.region);
  }
}

std::vector<EffectFrame> DeformationModel::drive(const std::vector<Pose>& poses,
                                                 const std::vector<BoneTransforms>& bones,
                                                 const std::vector<double>& breath,
                                                 const std::vector<double>& effort, double rate_hz) const {
  const size_t n = poses.size();
  if (bones.size() != n || breath.size() != n || effort.size() != n)
    throw std::invalid_argument("DeformationModel::drive: poses, bones, breath and effort differ in length");
  std::vector<EffectFrame> out(n, EffectFrame(regions_.size()));
  std::vector<std::vector<Vec3>> jig;
  if (options_.jiggle_scale != 0.0 && !jiggle_.empty()) jig = simulate_jiggle(jiggle_, bones, rate_hz);
  for (size_t f = 0; f < n; ++f) {
    size_t e = 0;
    for (const Muscle& m : muscles_)
      out[f][e++].normal_mm = options_.muscle_scale * muscle_bulge_mm(m, poses[f], effort[f]);
    for (const BreathingPart& b : breathing_)
      out[f][e++].normal_mm = options_.breath_scale * breathing_mm(b, breath[f]);
    for (size_t j = 0; j < jiggle_.size(); ++j, ++e)
      out[f][e].offset_mm = jig.empty() ? Vec3(Vec3::Zero()) : Vec3(options_.jiggle_scale * jig[j][f]);
  }
  return out;
}

DeformedSurface::DeformedSurface(std::vector<Vec3> rest, const std::vector<Face>& faces, SkinWeights weights,
                                 const DeformationModel& model)
    : rest_(std::move(rest)), weights_(std::move(weights)) {
  if (weights_.vertex_count() != static_cast<int>(rest_.size()))
    throw std::invalid_argument("DeformedSurface: weights and vertices differ in count");
  triangles_ = triangulate(faces, &triangle_face_);
  rest_normals_ = vertex_normals(rest_, triangles_);
  std::vector<std::vector<std::pair<int, double>>> rows(rest_.size());
  for (int e = 0; e < model.effect_count(); ++e) {
    const Footprint fp = footprint(model.regions()[static_cast<size_t>(e)], rest_, rest_normals_, weights_);
    for (size_t k = 0; k < fp.vertices.size(); ++k)
      rows[static_cast<size_t>(fp.vertices[k])].emplace_back(e, fp.weights[k]);
  }
  for (const auto& row : rows) {
    for (const auto& [e, w] : row) {
      effect_ids_.push_back(e);
      effect_weights_.push_back(w);
    }
    effect_offsets_.push_back(static_cast<int>(effect_ids_.size()));
  }
}

Vec3 DeformedSurface::vertex(int v, const BoneTransforms& bones, const EffectFrame& effects,
                             bool skin_only) const {
  Vec3 n;
  const Vec3 p = skin_vertex(weights_, v, rest_[static_cast<size_t>(v)], bones,
                             &rest_normals_[static_cast<size_t>(v)], &n);
  if (skin_only) return p;
  double along = 0.0;
  Vec3 offset = Vec3::Zero();
  for (int k = effect_offsets_[static_cast<size_t>(v)]; k < effect_offsets_[static_cast<size_t>(v) + 1];
       ++k) {
    const EffectValue& e = effects[static_cast<size_t>(effect_ids_[static_cast<size_t>(k)])];
    const double w = effect_weights_[static_cast<size_t>(k)];
    along += w * e.normal_mm;
    offset += w * e.offset_mm;
  }
  return p + along * n + offset;
}

void DeformedSurface::pose(const BoneTransforms& bones, const EffectFrame& effects, std::vector<Vec3>& out,
                           bool skin_only) const {
  out.resize(rest_.size());
  for (int v = 0; v < vertex_count(); ++v) out[static_cast<size_t>(v)] = vertex(v, bones, effects, skin_only);
}

double DeformedSurface::effect_magnitude(int v, const BoneTransforms& bones,
                                         const EffectFrame& effects) const {
  return (vertex(v, bones, effects) - vertex(v, bones, effects, true)).norm();
}

}  // namespace skinstream::synth
