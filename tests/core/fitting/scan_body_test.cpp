#include "core/fitting/scan_body.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <numeric>
#include <random>

#include "core/body/anatomy.h"
#include "core/body/skinning.h"
#include "core/synth/mannequin.h"

namespace skinstream {
namespace {

// A "scan" of another person: the mannequin with other proportions, in another pose (arms up in
// a T, knees bent, turned), its vertices shuffled and its skeleton dropped. `order[k]` is the
// template vertex that became scan vertex k.
struct Scan {
  std::vector<Vec3> vertices;
  std::vector<Triangle> triangles;
  std::vector<int> order;
};

Scan make_scan(const Body& body, const TemplateSegments& segments, uint32_t seed) {
  BodyProportions proportions = BodyProportions::neutral(segments);
  proportions.overall = 1.04;
  proportions.length[static_cast<size_t>(std::find(segments.shape_groups.begin(), segments.shape_groups.end(), "thigh") -
                                         segments.shape_groups.begin())] = 1.08;
  proportions.girth[static_cast<size_t>(std::find(segments.shape_groups.begin(), segments.shape_groups.end(), "abdomen") -
                                        segments.shape_groups.begin())] = 1.12;
  Body other = body;
  const std::vector<BoneMap> maps = proportion_bones(body.skeleton, segments, proportions);
  other.rest = proportioned_vertices(body.rest, body.weights, maps);
  const Anatomy anatomy = Anatomy::from(body);
  PoseBuilder pose(body.skeleton, anatomy);
  pose.shoulder(kLeft, 0.0, 90.0);
  pose.shoulder(kRight, 0.0, 90.0);
  pose.knee(kLeft, 25.0);
  pose.knee(kRight, 15.0);
  const std::vector<Vec3> posed = skin(other.rest, body.weights, pose_bones(body.skeleton, pose.pose()));
  Scan scan;
  scan.order.resize(posed.size());
  std::iota(scan.order.begin(), scan.order.end(), 0);
  std::mt19937 random(seed);
  std::shuffle(scan.order.begin(), scan.order.end(), random);
  std::vector<int> where(posed.size());
  for (size_t k = 0; k < posed.size(); ++k) where[static_cast<size_t>(scan.order[k])] = static_cast<int>(k);
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(0.5, Vec3::UnitZ()).toRotationMatrix();
  for (int v : scan.order) scan.vertices.push_back(turn * posed[static_cast<size_t>(v)]);
  for (const Triangle& t : triangulate(body.faces)) scan.triangles.push_back({where[t[0]], where[t[1]], where[t[2]]});
  return scan;
}

int dominant(const VertexSegmentWeights& w, int v, double* weight = nullptr) {
  int best = -1;
  double most = -1.0;
  for (int k = w.offsets[v]; k < w.offsets[v + 1]; ++k)
    if (w.weights[k].weight > most) most = w.weights[k].weight, best = w.weights[k].segment;
  if (weight) *weight = most;
  return best;
}

TEST(ScanBody, RefusesAnEmptyScan) {
  const Body body = synth::make_mannequin();
  const TemplateSegments segments = segment_template(body.skeleton);
  EXPECT_THROW(skin_scan(body, segments, {}, {}), std::invalid_argument);
}

// The template goes onto the scan, and the scan's vertices inherit the segments they belong to.
TEST(ScanBody, AScanInheritsTheTemplatesSegmentsWhateverItsPoseAndVertexOrder) {
  const Body body = synth::make_mannequin();
  const TemplateSegments segments = segment_template(body.skeleton);
  Scan scan = make_scan(body, segments, 3);
  // Upright and facing +Y, as detect_mesh_frame brings a scan: undo the turn.
  for (Vec3& v : scan.vertices) v = Eigen::AngleAxisd(-0.5, Vec3::UnitZ()).toRotationMatrix() * v;
  const ScanBody skinned = skin_scan(body, segments, scan.vertices, scan.triangles);
  const VertexSegmentWeights truth = segment_weights(body.weights, segments);
  // Where a segment clearly holds a vertex (70% of its weight or more), the scan's vertex has
  // that segment too; near joints, where two share it, a few millimetres decide.
  int clear = 0, same = 0;
  for (size_t k = 0; k < scan.vertices.size(); ++k) {
    double weight = 0.0;
    const int want = dominant(truth, scan.order[k], &weight);
    if (weight < 0.7) continue;
    ++clear;
    same += dominant(skinned.body.weights, static_cast<int>(k)) == want ? 1 : 0;
  }
  std::printf("fit %.1f mm, registered %.1f mm, scan to template median %.1f max %.1f mm, %d of %d clearly held vertices on their segment\n",
              skinned.fit_rms_mm, skinned.registered_rms_mm, skinned.inherited_median_mm, skinned.inherited_max_mm, same, clear);
  EXPECT_GE(same, static_cast<int>(0.97 * clear));
  EXPECT_LT(skinned.inherited_median_mm, 5.0);
  // The scan keeps its own surface and vertex order; its skeleton stands in its pose.
  EXPECT_EQ(skinned.body.rest, scan.vertices);
  EXPECT_EQ(skinned.body.segment_count(), segments.segment_count());
  const int upper = skinned.body.find("upperarm.L"), fore = skinned.body.find("forearm.L");
  const Vec3 arm = skinned.body.rest_pivots[fore] - skinned.body.rest_pivots[upper];
  EXPECT_LT(std::abs(arm.z()), 0.3 * arm.norm()) << "the left arm is raised to a T in the scan";
}

}  // namespace
}  // namespace skinstream
