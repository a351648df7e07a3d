#include "core/fitting/actor_fit.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "tests/core/fitting/synthetic_actor.h"

namespace skinstream {
namespace {

using test::Actor;
using test::guessed_priors;
using test::make_actor;

TEST(ActorFit, RefusesInputOfTheWrongShape) {
  const Actor a = make_actor(1, 30);
  const int markers = static_cast<int>(a.attachments.size());
  std::vector<MarkerPrior> priors(markers);
  EXPECT_THROW(fit_actor(test::fit_body(a), a.frames, a.frame_count + 1, markers, 0, priors),
               std::invalid_argument);
  EXPECT_THROW(fit_actor(test::fit_body(a), a.frames, a.frame_count, markers, a.frame_count, priors),
               std::invalid_argument);
  priors.pop_back();
  EXPECT_THROW(fit_actor(test::fit_body(a), a.frames, a.frame_count, markers, 0, priors),
               std::invalid_argument);
}

TEST(ActorFit, RecoversProportionsAndPlacesFromNamedMarkers) {
  const Actor a = make_actor(2, 240);
  std::mt19937 random(2);
  const std::vector<MarkerPrior> priors = guessed_priors(a, random);
  const int markers = static_cast<int>(a.attachments.size());
  const ActorFit fit = fit_actor(test::fit_body(a), a.frames, a.frame_count, markers, 0, priors);
  EXPECT_FALSE(fit.blind);
  EXPECT_LT(fit.rms_mm, 3.0);
  EXPECT_NEAR(fit.proportions.overall, a.proportions.overall, 0.05);
  // Where each marker sits, compared on the true body at the reference frame.
  const std::vector<BoneMap> maps = proportion_bones(a.body.skeleton, a.segments, a.proportions);
  const std::vector<Vec3> true_rest = proportioned_vertices(a.body.rest, a.body.weights, maps);
  double worst = 0.0, sum = 0.0;
  for (int i = 0; i < markers; ++i) {
    const double d = (skin_point(fit.attachments[i], fit.rest_vertices, a.triangles) -
                      skin_point(a.attachments[i], true_rest, a.triangles)).norm();
    worst = std::max(worst, d);
    sum += d;
  }
  // The guesses were 25 mm off each; the fit halves that on average and moves none farther.
  EXPECT_LT(sum / markers, 12.5);
  EXPECT_LT(worst, 25.0);
}

TEST(ActorFit, PlacesUnnamedMarkersFromABlindStart) {
  const Actor a = make_actor(3, 240);
  const int markers = static_cast<int>(a.attachments.size());
  const std::vector<MarkerPrior> priors(markers);
  const ActorFit fit = fit_actor(test::fit_body(a), a.frames, a.frame_count, markers, 0, priors);
  EXPECT_TRUE(fit.blind);
  const std::vector<BoneMap> maps = proportion_bones(a.body.skeleton, a.segments, a.proportions);
  const std::vector<Vec3> true_rest = proportioned_vertices(a.body.rest, a.body.weights, maps);
  std::vector<double> off;
  for (int i = 0; i < markers; ++i)
    off.push_back((skin_point(fit.attachments[i], fit.rest_vertices, a.triangles) - skin_point(a.attachments[i], true_rest, a.triangles)).norm());
  // Without names, a marker's place along the skin is free where the body's shape does not pin
  // it; it must land on the right segment, and the markers still be followed.
  const VertexSegmentWeights w = segment_weights(a.body.weights, a.segments);
  auto dominant = [&](const MarkerAttachment& m) {
    std::vector<SegmentWeight> weights;
    attachment_segment_weights(m, a.triangles, w, weights);
    return std::max_element(weights.begin(), weights.end(), [](auto& x, auto& y) { return x.weight < y.weight; })->segment;
  };
  auto joints_apart = [&](int x, int y) {  // along the segment tree
    std::vector<int> up_x;
    for (int s = x; s >= 0; s = a.segments.segments[s].parent) up_x.push_back(s);
    for (int steps = 0, s = y; s >= 0; s = a.segments.segments[s].parent, ++steps) {
      const auto found = std::find(up_x.begin(), up_x.end(), s);
      if (found != up_x.end()) return steps + static_cast<int>(found - up_x.begin());
    }
    return 99;
  };
  int right_segment = 0, near = 0;
  for (int i = 0; i < markers; ++i) {
    const int apart = joints_apart(dominant(fit.attachments[i]), dominant(a.attachments[i]));
    right_segment += apart == 0 ? 1 : 0;
    near += apart <= 2 ? 1 : 0;
  }
  std::sort(off.begin(), off.end());
  std::printf("blind: rms %.1f mm, places %.1f mm off (median), %d of %d on the right segment, %d within two joints\n",
              fit.rms_mm, off[off.size() / 2], right_segment, markers, near);
  // Measured: 46 of 54 right, 7 one joint away, one chest marker by the armpit on the upper arm.
  EXPECT_GE(right_segment, markers * 8 / 10);
  EXPECT_EQ(near, markers);
  EXPECT_LT(fit.rms_mm, 20.0);
}

}  // namespace
}  // namespace skinstream
