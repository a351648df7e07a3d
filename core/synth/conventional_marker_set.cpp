#include "core/synth/conventional_marker_set.h"

#include <algorithm>
#include <limits>
#include <stdexcept>

#include "core/baselines/bone_heat_weights.h"
#include "core/body/anatomy.h"

namespace skinstream::synth {

int ConventionalMarkerSet::marker_count() const {
  int count = 0;
  for (const auto& set : skinning.segment_markers) count += static_cast<int>(set.size());
  return count;
}

namespace {

// Segment roots: a bone belongs to the segment of its nearest ancestor (itself included) that
// is a root. The clavicles and shoulder blades ride with the thorax, as in Plug-in Gait.
std::vector<std::pair<std::string, int>> segment_roots(const Anatomy& a) {
  std::vector<std::pair<std::string, int>> roots = {
      {"pelvis", a.root >= 0 ? a.root : a.spine[0]}, {"thorax", a.spine[2]}, {"head", a.neck[0]}};
  for (Side s : {kLeft, kRight}) {
    const std::string side = std::string(".") + side_suffix(s);
    roots.push_back({"upperarm" + side, a.arm[s].upperarm});
    roots.push_back({"forearm" + side, a.arm[s].elbow});
    roots.push_back({"hand" + side, a.arm[s].wrist});
    roots.push_back({"thigh" + side, a.leg[s].hip});
    roots.push_back({"shank" + side, a.leg[s].knee});
    roots.push_back({"foot" + side, a.leg[s].ankle});
  }
  return roots;
}

}  // namespace

ConventionalMarkerSet choose_conventional_markers(const Body& body, const SynthCapture& training,
                                                  const SkinWeights& weights, int per_segment) {
  const Anatomy anatomy = Anatomy::from(body);
  const Skeleton& skeleton = body.skeleton;
  ConventionalMarkerSet set;
  const auto roots = segment_roots(anatomy);
  std::vector<int> root_bone;
  for (const auto& [name, bone] : roots) {
    if (bone < 0) continue;
    set.segment_names.push_back(name);
    root_bone.push_back(bone);
  }
  // A bone belongs to the segment of its nearest root ancestor. Segments that carry too few
  // markers (the dense set has none on the head, hands and feet) are dropped and their bones
  // ride with the parent segment, as a technician would do without those markers.
  const int markers = static_cast<int>(training.markers.size());
  auto assign_bones = [&] {
    set.bone_segment.assign(static_cast<size_t>(skeleton.size()), 0);
    for (int b = 0; b < skeleton.size(); ++b)
      for (int cursor = b; cursor >= 0; cursor = skeleton.bone(cursor).parent) {
        const auto it = std::find(root_bone.begin(), root_bone.end(), cursor);
        if (it != root_bone.end()) {
          set.bone_segment[b] = static_cast<int>(it - root_bone.begin());
          break;
        }
      }
  };
  assign_bones();
  std::vector<int> count(root_bone.size(), 0);
  for (int m = 0; m < markers; ++m) ++count[set.bone_segment[training.markers[m].dominant_bone]];
  for (int s = static_cast<int>(root_bone.size()) - 1; s > 0; --s)
    if (count[s] < per_segment) {
      root_bone.erase(root_bone.begin() + s);
      set.segment_names.erase(set.segment_names.begin() + s);
    }
  assign_bones();
  const int segments = static_cast<int>(root_bone.size());

  // How far each marker strays from its segment's bone over the take: RMS of its position in
  // the root bone's rest frame around the mean.
  const int frames = training.frame_count();
  const int stride = std::max(1, frames / 120);
  std::vector<int> marker_segment(markers);
  std::vector<Vec3> sum(markers, Vec3::Zero());
  std::vector<double> sum_squares(markers, 0.0);
  int samples = 0;
  for (int f = 0; f < frames; f += stride, ++samples) {
    const BoneTransforms bones = pose_bones(skeleton, training.pose(f));
    for (int m = 0; m < markers; ++m) {
      marker_segment[m] = set.bone_segment[training.markers[m].dominant_bone];
      const Vec3 local = bones[root_bone[marker_segment[m]]].inverse() * training.truth.at(f, m);
      sum[m] += local;
      sum_squares[m] += local.squaredNorm();
    }
  }
  std::vector<double> stray(markers);
  for (int m = 0; m < markers; ++m)
    stray[m] = std::sqrt(std::max(0.0, sum_squares[m] / samples - (sum[m] / samples).squaredNorm()));

  // Per segment: the steadiest marker first, then the steadier half of the rest picked far apart.
  set.skinning.segment_markers.assign(segments, {});
  for (int s = 0; s < segments; ++s) {
    std::vector<int> candidates;
    for (int m = 0; m < markers; ++m)
      if (marker_segment[m] == s) candidates.push_back(m);
    if (static_cast<int>(candidates.size()) < per_segment)
      throw std::invalid_argument("segment " + set.segment_names[s] + " has only " + std::to_string(candidates.size()) +
                                  " markers");
    std::sort(candidates.begin(), candidates.end(), [&](int a, int b) { return stray[a] < stray[b] || (stray[a] == stray[b] && a < b); });
    candidates.resize(std::max<size_t>(per_segment, candidates.size() / 2));
    auto& chosen = set.skinning.segment_markers[s];
    chosen.push_back(candidates.front());
    while (static_cast<int>(chosen.size()) < per_segment) {
      int best = -1;
      double best_distance = -1.0;
      for (int c : candidates) {
        if (std::find(chosen.begin(), chosen.end(), c) != chosen.end()) continue;
        double nearest = std::numeric_limits<double>::infinity();
        for (int k : chosen) nearest = std::min(nearest, (training.markers[c].rest_position - training.markers[k].rest_position).norm());
        if (nearest > best_distance) {
          best_distance = nearest;
          best = c;
        }
      }
      chosen.push_back(best);
    }
  }

  // Skin weights summed per segment.
  auto& offsets = set.skinning.vertex_weight_offsets;
  auto& entries = set.skinning.vertex_weights;
  std::vector<double> per_segment_weight(segments);
  for (int v = 0; v < weights.vertex_count(); ++v) {
    std::fill(per_segment_weight.begin(), per_segment_weight.end(), 0.0);
    for (int k = weights.begin(v); k < weights.end(v); ++k) per_segment_weight[set.bone_segment[weights.bones[k]]] += weights.weights[k];
    double total = 0.0;
    for (double w : per_segment_weight) total += w;
    for (int s = 0; s < segments; ++s)
      if (per_segment_weight[s] > 0.0) entries.push_back({s, per_segment_weight[s] / total});
    offsets.push_back(static_cast<int>(entries.size()));
  }
  return set;
}

SegmentSkinningModel bone_heat_skinning(const Body& body, const ConventionalMarkerSet& set) {
  std::vector<HeatBone> bones;
  for (int b = 0; b < body.skeleton.size(); ++b)
    bones.push_back({body.skeleton.bone(b).head, body.skeleton.bone(b).tail, set.bone_segment[b]});
  SegmentSkinningModel model = set.skinning;
  bone_heat_weights(body.rest, triangulate(body.faces), bones, static_cast<int>(set.segment_names.size()), {},
                    model.vertex_weight_offsets, model.vertex_weights);
  return model;
}

}  // namespace skinstream::synth
