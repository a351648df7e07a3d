#include "core/deform/body_plausibility.h"

#include <gtest/gtest.h>

#include "core/geometry/triangle_mesh.h"
#include "core/synth/mannequin.h"

namespace skinstream {
namespace {

struct Loaded {
  SubjectModel subject;
  DeformationModel model;
};

// The mannequin as a loaded subject's body, at rest, with markers 10 mm above some of its vertices.
Loaded mannequin_subject() {
  const Body body = synth::make_mannequin();
  Loaded l;
  l.model.faces = triangulate(body.faces);
  l.model.reference_vertices = body.rest;
  l.model.rest_vertices = body.rest;
  const std::vector<Vec3> normals = vertex_normals(body.rest, l.model.faces);
  for (int v = 0; v < body.vertex_count(); v += 97) l.subject.reference_positions.push_back(body.rest[v] + 10.0 * normals[v]);
  return l;
}

TEST(BodyPlausibility, ABodyAtRestWithItsMarkersOnItIsPlausible) {
  const Loaded l = mannequin_subject();
  EXPECT_EQ(implausible_body(l.subject, l.model), "");
}

TEST(BodyPlausibility, ATornBodyIsRefused) {
  Loaded l = mannequin_subject();
  for (int v : {10, 1000, 2000}) l.model.reference_vertices[v] += Vec3(0, 1200, 900);  // 1.5 m: 40 of the mannequin's edges
  EXPECT_NE(implausible_body(l.subject, l.model).find("torn"), std::string::npos) << implausible_body(l.subject, l.model);
}

TEST(BodyPlausibility, ACrumpledBodyIsRefused) {
  Loaded l = mannequin_subject();
  for (size_t v = 0; v < l.model.reference_vertices.size(); ++v)
    l.model.reference_vertices[v] += 12.0 * Vec3(std::sin(1.7 * v), std::cos(2.3 * v), std::sin(0.9 * v + 1.0));
  EXPECT_NE(implausible_body(l.subject, l.model).find("crumpled"), std::string::npos) << implausible_body(l.subject, l.model);
}

TEST(BodyPlausibility, MarkersAwayFromTheBodyAreRefused) {
  Loaded l = mannequin_subject();
  for (Vec3& m : l.subject.reference_positions) m += Vec3(500, 0, 0);  // the body half a metre off its markers
  EXPECT_NE(implausible_body(l.subject, l.model).find("not on the body"), std::string::npos);
  // Without rest vertices (a mesh registered as given) the marker check still runs.
  l.model.rest_vertices.clear();
  EXPECT_NE(implausible_body(l.subject, l.model).find("not on the body"), std::string::npos);
}

}  // namespace
}  // namespace skinstream
