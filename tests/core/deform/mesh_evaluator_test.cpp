#include "core/deform/mesh_evaluator.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/deform/mesh_deformer.h"
#include "core/deform/rbf_kernel.h"
#include "tests/core/deform/deform_test_support.h"
#include "tests/support/allocation_counter.h"

namespace skinstream {
namespace {

using deform_test::WavySheet;

// docs/subscriber-protocol.md's evaluation of one vertex, written out in double from the spec's
// pseudocode alone (no clusters, no culling, no vector lanes): what every renderer implements.
Vec3 evaluate_as_specified(const EvaluationModel& model, const FrameParameters& frame, int j) {
  Vec3 v = Vec3::Zero();
  for (int k = model.influence_offsets[j]; k < model.influence_offsets[j + 1]; ++k) {
    const int p = model.influence_parts[k];
    const EvaluationPart& part = model.parts[p];
    const PartParameters& params = frame.parts[p];
    Vec3 u, s;
    for (int r = 0; r < 3; ++r) {
      u[r] = part.translation[r];
      for (int c = 0; c < 3; ++c) u[r] += double(part.rotation[3 * r + c]) * model.reference_vertices[3 * j + c];
      s[r] = std::clamp(u[r], double(part.box_min[r]), double(part.box_max[r]));
    }
    auto quadratic = [&](const Vec3& x) {
      const double q[9] = {x[0], x[1], x[2], x[0] * x[0], x[1] * x[1], x[2] * x[2], x[0] * x[1], x[1] * x[2], x[2] * x[0]};
      Vec3 out = Vec3::Zero();
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 9; ++c) out[r] += double(params.quadratic[9 * r + c]) * q[c];
      return out;
    };
    Vec3 l = quadratic(s);
    if (params.rbf && part.sigma > 0) {
      Vec3 sum = Vec3::Zero();
      const int first = model.first_member(p);
      for (int i = 0; i < part.member_count; ++i) {
        const float* p0 = &model.member_reference[3 * (first + i)];
        const Vec3 c = quadratic(Vec3(p0[0], p0[1], p0[2]));
        const double phi = cubic_bspline_kernel((l - c).norm() / part.sigma);
        for (int a = 0; a < 3; ++a) sum[a] += phi * frame.weights[3 * (first + i) + a];
      }
      l += sum;
    }
    const Vec3 local = l + (u - s);
    Vec3 world;
    for (int r = 0; r < 3; ++r) {
      world[r] = 0.0;
      for (int c = 0; c < 3; ++c) world[r] += double(params.rotation[3 * c + r]) * (local[c] - params.translation[c]);  // R^T
    }
    v += double(model.influence_weights[k]) * world;
  }
  return v;
}

// The sheet bent, stretched and moved: the markers the parts are fitted to.
std::vector<Vec3> bent_markers(const SubjectModel& subject) {
  std::vector<Vec3> markers;
  for (const Vec3& m : subject.reference_positions)
    markers.push_back(Vec3(m.x() * 1.05 + 30.0, m.y() + 0.002 * m.x() * m.x(), m.z() + 20.0 * std::sin(m.y() / 60.0) + 500.0));
  return markers;
}

TEST(MeshEvaluator, TheDeformersFrameEqualsTheSpecifiedEvaluationOfItsParameters) {
  WavySheet sheet;
  MeshDeformer deformer(sheet.model, sheet.subject);
  std::vector<float> positions(3 * static_cast<size_t>(deformer.vertex_count())), normals(positions.size());
  ASSERT_TRUE(deformer.deform(bent_markers(sheet.subject), positions, normals));
  const EvaluationModel& model = deformer.evaluation_model();
  const FrameParameters& frame = deformer.parameters();
  bool any_rbf = false;
  for (const PartParameters& p : frame.parts) any_rbf |= p.rbf;
  ASSERT_TRUE(any_rbf) << "the test must exercise the RBF term";
  double worst = 0.0;
  for (int j = 0; j < model.vertex_count(); ++j) {
    const Vec3 expected = evaluate_as_specified(model, frame, j);
    for (int a = 0; a < 3; ++a) worst = std::max(worst, std::abs(expected[a] - positions[3 * j + a]));
  }
  // Float evaluation of mm-sized coordinates against double: far below the 0.01 mm promised.
  EXPECT_LT(worst, 1e-3);

  // A second evaluator built from the same model and given the same parameters (as a renderer
  // is) reproduces the daemon's buffer bit for bit.
  MeshEvaluator renderer(model);
  std::vector<float> again(positions.size()), again_normals(positions.size());
  ASSERT_TRUE(renderer.evaluate(frame, again, again_normals));
  EXPECT_EQ(again, positions);
  EXPECT_EQ(again_normals, normals);
}

TEST(MeshEvaluator, RestParametersGiveTheReferenceMesh) {
  WavySheet sheet;
  MeshDeformer deformer(sheet.model, sheet.subject);
  const EvaluationModel& model = deformer.evaluation_model();
  MeshEvaluator evaluator(model);
  std::vector<float> positions(model.reference_vertices.size());
  ASSERT_TRUE(evaluator.evaluate(rest_parameters(model), positions, {}));
  for (size_t i = 0; i < positions.size(); ++i) EXPECT_NEAR(positions[i], model.reference_vertices[i], 1e-3) << i;
}

TEST(MeshEvaluator, EvaluatesWithoutAllocatingAndRefusesParametersThatDoNotFit) {
  WavySheet sheet;
  MeshDeformer deformer(sheet.model, sheet.subject);
  ASSERT_TRUE(deformer.solve_parts(bent_markers(sheet.subject)));
  MeshEvaluator evaluator(deformer.evaluation_model());
  FrameParameters frame = deformer.parameters();
  std::vector<float> positions(3 * static_cast<size_t>(evaluator.vertex_count())), normals(positions.size());
  {
    test::CountAllocations count;
    ASSERT_TRUE(evaluator.evaluate(frame, positions, normals));
    EXPECT_EQ(count.count(), 0u);
  }
  const std::vector<float> good = positions;
  FrameParameters short_frame = frame;
  short_frame.weights.pop_back();
  EXPECT_FALSE(evaluator.evaluate(short_frame, positions, normals));
  FrameParameters nan_frame = frame;
  nan_frame.parts[1].quadratic[4] = std::nanf("");
  EXPECT_FALSE(evaluator.evaluate(nan_frame, positions, normals));
  EXPECT_EQ(positions, good);  // refused frames leave the previous result
}

// Found by fuzzing (tests/fuzz/subscriber_model_fuzz.cpp, a decoded Model evaluated before its
// MeshInfo gave it faces): four vertices of a block of lanes in no face made a block of one row,
// and the normals read the next row past the end (AddressSanitizer: heap-buffer-overflow). A
// vertex in no face now gets a zero normal, one in a face a unit one.
TEST(MeshEvaluator, VerticesInNoFaceGetAZeroNormal) {
  WavySheet sheet;
  MeshDeformer deformer(sheet.model, sheet.subject);
  const EvaluationModel& whole = deformer.evaluation_model();
  std::vector<float> positions(whole.reference_vertices.size());

  EvaluationModel one_face = whole;
  one_face.faces.resize(1);
  EvaluationModel no_faces = whole;
  no_faces.faces.clear();
  for (const EvaluationModel* model : {&one_face, &no_faces}) {
    MeshEvaluator evaluator(*model);
    std::vector<float> normals(positions.size(), 7.0f);
    ASSERT_TRUE(evaluator.evaluate(rest_parameters(*model), positions, normals));
    for (int v = 0; v < model->vertex_count(); ++v) {
      const std::array<int, 3>* face = model->faces.empty() ? nullptr : &model->faces[0];
      const bool in_face = face && ((*face)[0] == v || (*face)[1] == v || (*face)[2] == v);
      const float length = std::hypot(normals[3 * v], normals[3 * v + 1], normals[3 * v + 2]);
      if (in_face)
        EXPECT_NEAR(length, 1.0f, 1e-5f) << v;
      else
        EXPECT_EQ(length, 0.0f) << v;
    }
  }
}

TEST(EvaluationModel, ValidateNamesWhatIsInconsistent) {
  WavySheet sheet;
  MeshDeformer deformer(sheet.model, sheet.subject);
  const EvaluationModel good = deformer.evaluation_model();
  ASSERT_EQ(good.validate(), "");
  auto expect_problem = [&](const char* what, auto&& spoil) {
    EvaluationModel model = good;
    spoil(model);
    const std::string problem = model.validate();
    EXPECT_NE(problem.find(what), std::string::npos) << "expected \"" << what << "\", got \"" << problem << "\"";
    EXPECT_THROW(MeshEvaluator{model}, std::invalid_argument);
  };
  expect_problem("refers to vertex", [](EvaluationModel& m) { m.faces[3][1] = m.vertex_count(); });
  expect_problem("influenced by part 2", [](EvaluationModel& m) { m.influence_parts[0] = 2; });
  expect_problem("sum to", [](EvaluationModel& m) { m.influence_weights[0] *= 0.5f; });
  expect_problem("members", [](EvaluationModel& m) { m.parts[0].member_count += 1; });
  expect_problem("not orthonormal", [](EvaluationModel& m) { m.parts[1].rotation[0] = 2.0f; });
  expect_problem("box is empty", [](EvaluationModel& m) { m.parts[0].box_min[2] = m.parts[0].box_max[2] + 1.0f; });
  expect_problem("not finite", [](EvaluationModel& m) { m.reference_vertices[7] = std::nanf(""); });
  expect_problem("influence offsets", [](EvaluationModel& m) { m.influence_offsets.pop_back(); });
  expect_problem("no influence", [](EvaluationModel& m) {
    // Vertex 0's influences handed to vertex 1.
    m.influence_offsets[1] = 0;
  });
}

}  // namespace
}  // namespace skinstream
