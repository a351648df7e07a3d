#include "core/fitting/template_segments.h"

#include <algorithm>
#include <map>
#include <stdexcept>

namespace skinstream {

int TemplateSegments::find(const std::string& name) const {
  for (int s = 0; s < segment_count(); ++s)
    if (segments[s].name == name) return s;
  return -1;
}

TemplateSegments segment_template(const Skeleton& skeleton) {
  TemplateSegments out;
  out.shape_groups = {"pelvis", "abdomen", "chest", "head", "clavicle", "upperarm", "forearm", "hand", "thigh", "shank", "foot"};
  auto group = [&](const std::string& name) {
    return static_cast<int>(std::find(out.shape_groups.begin(), out.shape_groups.end(), name) - out.shape_groups.begin());
  };
  auto add = [&](const std::string& name, const std::string& bone, const std::string& parent, const std::string& shape) {
    const int b = skeleton.find(bone);
    if (b < 0) throw std::invalid_argument("the template's skeleton has no bone " + bone + " (not a MakeHuman-style skeleton)");
    const int p = parent.empty() ? -1 : out.find(parent);
    out.segments.push_back({name, b, p, group(shape)});
  };
  add("pelvis", "root", "", "pelvis");
  add("abdomen", "spine04", "pelvis", "abdomen");
  add("chest", "spine02", "abdomen", "chest");
  add("head", "neck01", "chest", "head");
  for (const char* side : {"L", "R"}) {
    const std::string s = std::string(".") + side;
    add("clavicle" + s, "clavicle" + s, "chest", "clavicle");
    add("upperarm" + s, "upperarm01" + s, "clavicle" + s, "upperarm");
    add("forearm" + s, "lowerarm01" + s, "upperarm" + s, "forearm");
    add("hand" + s, "wrist" + s, "forearm" + s, "hand");
    add("thigh" + s, "upperleg01" + s, "pelvis", "thigh");
    add("shank" + s, "lowerleg01" + s, "thigh" + s, "shank");
    add("foot" + s, "foot" + s, "shank" + s, "foot");
  }
  // Parents first: the sided segments were added side by side, each after its parent.
  std::map<int, int> segment_of_first_bone;
  for (int s = 0; s < out.segment_count(); ++s) segment_of_first_bone[out.segments[s].first_bone] = s;
  out.bone_segment.assign(static_cast<size_t>(skeleton.size()), -1);
  for (int b = 0; b < skeleton.size(); ++b) {
    int bone = b;
    while (bone >= 0 && !segment_of_first_bone.count(bone)) bone = skeleton.bone(bone).parent;
    // A bone above every segment's first bone (none in MakeHuman's tree) rides with the pelvis.
    out.bone_segment[b] = bone >= 0 ? segment_of_first_bone[bone] : 0;
  }
  // Each segment's first bone must descend from its parent segment's, or the chain is not a tree
  // of these segments.
  for (const TemplateSegment& s : out.segments)
    if (s.parent >= 0 && !skeleton.is_descendant(s.first_bone, out.segments[s.parent].first_bone))
      throw std::invalid_argument("the template's skeleton has bone " + skeleton.bone(s.first_bone).name +
                                  " outside the chain of " + skeleton.bone(out.segments[s.parent].first_bone).name);
  return out;
}

VertexSegmentWeights segment_weights(const SkinWeights& weights, const TemplateSegments& segments) {
  VertexSegmentWeights out;
  out.offsets.reserve(static_cast<size_t>(weights.vertex_count()) + 1);
  std::vector<double> sum(static_cast<size_t>(segments.segment_count()), 0.0);
  std::vector<int> touched;
  for (int v = 0; v < weights.vertex_count(); ++v) {
    double total = 0.0;
    for (int k = weights.begin(v); k < weights.end(v); ++k) {
      const int s = segments.bone_segment[static_cast<size_t>(weights.bones[static_cast<size_t>(k)])];
      if (sum[static_cast<size_t>(s)] == 0.0) touched.push_back(s);
      sum[static_cast<size_t>(s)] += weights.weights[static_cast<size_t>(k)];
      total += weights.weights[static_cast<size_t>(k)];
    }
    std::sort(touched.begin(), touched.end());
    for (int s : touched) {
      if (total > 0.0) out.weights.push_back({s, sum[static_cast<size_t>(s)] / total});
      sum[static_cast<size_t>(s)] = 0.0;
    }
    touched.clear();
    out.offsets.push_back(static_cast<int>(out.weights.size()));
  }
  return out;
}

}  // namespace skinstream
