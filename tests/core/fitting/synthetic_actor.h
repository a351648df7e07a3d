#pragma once
// A synthetic actor for the fitting tests: the procedural mannequin in other proportions, markers
// at known places on it, a take of smooth random poses (linear blend skinning of the markers, as
// the fit models them, plus 0.5 mm of noise), and guesses of the places a marker set would give.
#include <Eigen/Geometry>
#include <algorithm>
#include <random>

#include "core/deform/skeleton_solver.h"
#include "core/fitting/actor_fit.h"
#include "core/geometry/triangle_bvh.h"
#include "core/synth/mannequin.h"

namespace skinstream::test {

// A synthetic actor on the procedural mannequin: other proportions, markers at known places,
// a take of smooth random poses. The fit must recover where the markers sit and how the body
// is proportioned from the measurements alone.
struct Actor {
  Body body;
  std::vector<Triangle> triangles;
  TemplateSegments segments;
  BodyProportions proportions;
  std::vector<MarkerAttachment> attachments;
  std::vector<Vec3> frames;  // frame-major
  int frame_count = 0;
  std::vector<SegmentPose> poses;
};

// Markers spread over each segment: the triangles most often dominated by it, farthest apart.
inline std::vector<MarkerAttachment> spread_markers(const Actor& a, int per_segment, std::mt19937& random) {
  const VertexSegmentWeights w = segment_weights(a.body.weights, a.segments);
  std::vector<MarkerAttachment> out;
  std::uniform_real_distribution<double> offset(8.0, 13.0);
  for (int s = 0; s < a.segments.segment_count(); ++s) {
    std::vector<int> candidates;
    for (size_t t = 0; t < a.triangles.size(); ++t) {
      bool all = true;
      for (int v : a.triangles[t]) {
        double mine = 0.0;
        for (int k = w.offsets[v]; k < w.offsets[v + 1]; ++k)
          if (w.weights[k].segment == s) mine = w.weights[k].weight;
        all = all && mine > 0.8;
      }
      if (all) candidates.push_back(static_cast<int>(t));
    }
    if (candidates.empty()) continue;
    std::vector<int> chosen = {candidates[random() % candidates.size()]};
    auto centroid = [&](int t) {
      return (a.body.rest[a.triangles[t][0]] + a.body.rest[a.triangles[t][1]] + a.body.rest[a.triangles[t][2]]) / 3.0;
    };
    while (static_cast<int>(chosen.size()) < per_segment) {
      int best = -1;
      double far = -1.0;
      for (int t : candidates) {
        double nearest = 1e30;
        for (int c : chosen) nearest = std::min(nearest, (centroid(t) - centroid(c)).norm());
        if (nearest > far) {
          far = nearest;
          best = t;
        }
      }
      chosen.push_back(best);
    }
    for (int t : chosen) out.push_back({t, Vec3::Constant(1.0 / 3.0), offset(random)});
  }
  return out;
}

inline Actor make_actor(uint32_t seed, int frames) {
  Actor a;
  a.body = synth::make_mannequin();
  a.triangles = triangulate(a.body.faces);
  a.segments = segment_template(a.body.skeleton);
  std::mt19937 random(seed);
  a.proportions = BodyProportions::neutral(a.segments);
  std::uniform_real_distribution<double> scale(0.9, 1.1);
  a.proportions.overall = 1.05;
  for (size_t g = 0; g < a.proportions.length.size(); ++g) {
    a.proportions.length[g] = scale(random);
    a.proportions.girth[g] = a.proportions.length[g] * std::clamp(scale(random), 0.95, 1.05);
  }
  a.attachments = spread_markers(a, 3, random);
  const std::vector<BoneMap> maps = proportion_bones(a.body.skeleton, a.segments, a.proportions);
  const std::vector<Vec3> rest = proportioned_vertices(a.body.rest, a.body.weights, maps);
  const std::vector<Vec3> pivots = proportioned_pivots(a.body.skeleton, a.segments, maps);
  const VertexSegmentWeights vw = segment_weights(a.body.weights, a.segments);
  SegmentSkeleton skeleton;
  for (int s = 0; s < a.segments.segment_count(); ++s)
    skeleton.segments.push_back({a.segments.segments[s].name, a.segments.segments[s].parent, pivots[s]});
  std::vector<Vec3> rest_markers;
  for (const MarkerAttachment& m : a.attachments) {
    rest_markers.push_back(attached_position(m, rest, a.triangles));
    attachment_segment_weights(m, a.triangles, vw, skeleton.marker_weights);
    skeleton.marker_weight_offsets.push_back(static_cast<int>(skeleton.marker_weights.size()));
  }
  // Keyframes every 30 frames; the first raises the arms (a T pose: the template stands in an A).
  std::normal_distribution<double> normal(0.0, 1.0);
  auto random_local = [&](double degrees) {
    const Vec3 axis = Vec3(normal(random), normal(random), normal(random)).normalized();
    return Eigen::Quaterniond(Eigen::AngleAxisd(degrees * M_PI / 180.0 * std::min(1.0, std::abs(normal(random))), axis));
  };
  const int segments = a.segments.segment_count();
  std::vector<std::vector<Eigen::Quaterniond>> keys;
  std::vector<Vec3> key_translation;
  for (int k = 0; k <= frames / 30 + 1; ++k) {
    std::vector<Eigen::Quaterniond> key;
    for (int s = 0; s < segments; ++s) key.push_back(random_local(35.0));
    key[0] = Eigen::Quaterniond(Eigen::AngleAxisd(normal(random), Vec3::UnitZ()));
    if (k == 0) {
      for (const char* side : {"L", "R"}) {
        const int upper = a.segments.find(std::string("upperarm.") + side);
        const double sign = side[0] == 'L' ? 1.0 : -1.0;
        key[upper] = Eigen::Quaterniond(Eigen::AngleAxisd(sign * 45.0 * M_PI / 180.0, Vec3::UnitY()));
      }
    }
    keys.push_back(key);
    key_translation.push_back(Vec3(300.0 * normal(random), 300.0 * normal(random), 0.0));
  }
  SkeletonSolver truth(skeleton, rest_markers);
  std::normal_distribution<double> noise(0.0, 0.5);
  for (int f = 0; f < frames; ++f) {
    const int k = f / 30;
    const double t = (f % 30) / 30.0;
    SegmentPose pose;
    for (int s = 0; s < segments; ++s) pose.local.push_back(keys[k][s].slerp(t, keys[k + 1][s]).toRotationMatrix());
    pose.translation = (1.0 - t) * key_translation[k] + t * key_translation[k + 1];
    truth.set_pose(pose.local, pose.translation);
    for (int i = 0; i < truth.marker_count(); ++i)
      a.frames.push_back(truth.predicted_marker(i) + Vec3(noise(random), noise(random), noise(random)));
    a.poses.push_back(pose);
  }
  a.frame_count = frames;
  return a;
}

// A marker set's guess of each place: the true skin point moved about 25 mm along the skin,
// allowed to move back within 60 mm.
inline std::vector<MarkerPrior> guessed_priors(const Actor& a, std::mt19937& random) {
  const TriangleBvh bvh(a.body.rest, a.triangles);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<MarkerPrior> priors;
  for (const MarkerAttachment& m : a.attachments) {
    const Vec3 skin = skin_point(m, a.body.rest, a.triangles);
    const Vec3 moved = skin + 25.0 * Vec3(normal(random), normal(random), normal(random)).normalized();
    MarkerPrior prior;
    Vec3 point;
    bvh.closest(moved, &prior.place.triangle, &point);
    const Triangle& t = a.triangles[prior.place.triangle];
    closest_point_on_triangle(moved, a.body.rest[t[0]], a.body.rest[t[1]], a.body.rest[t[2]], &prior.place.barycentric);
    for (size_t k = 0; k < a.triangles.size(); ++k)
      for (int v : a.triangles[k])
        if ((a.body.rest[v] - point).norm() < 60.0) {
          prior.allowed_triangles.push_back(static_cast<int>(k));
          break;
        }
    priors.push_back(prior);
  }
  return priors;
}

// The actor's template as the fit sees it (its body and segments must outlive the result).
inline FitBody fit_body(const Actor& a) { return fit_body_of(a.body, a.segments); }

}  // namespace skinstream::test
