#include "server/pipeline/deform_workers.h"

#include <gtest/gtest.h>

#include <random>

#include "tests/core/deform/deform_test_support.h"

namespace skinstream::server {
namespace {

// The workers only share out the stages of MeshDeformer::deform, each element computed by the
// same code whichever thread takes it: the result must be bit for bit the single-thread frame,
// for any thread count, frame after frame (the workers are reused).
TEST(DeformWorkers, AnyThreadCountGivesTheSingleThreadFrameBitForBit) {
  deform_test::WavySheet sheet;
  const size_t floats = sheet.model.reference_vertices.size() * 3;
  MeshDeformer reference(sheet.model, sheet.subject);
  for (int threads : {1, 2, 3}) {
    MeshDeformer deformer(sheet.model, sheet.subject);
    DeformWorkers workers(deformer, threads);
    EXPECT_EQ(workers.threads(), threads);
    std::mt19937_64 rng(4);
    for (int frame = 0; frame < 5; ++frame) {
      const std::vector<Vec3> now =
          deform_test::deform_non_rigidly(sheet.subject.reference_positions, deform_test::random_motion(rng));
      std::vector<float> positions(floats), normals(floats), expected_positions(floats), expected_normals(floats);
      ASSERT_TRUE(reference.deform(now, expected_positions, expected_normals));
      ASSERT_TRUE(deformer.solve_parts(now));
      workers.run(positions, normals);
      EXPECT_EQ(positions, expected_positions) << threads << " threads, frame " << frame;
      EXPECT_EQ(normals, expected_normals) << threads << " threads, frame " << frame;
      // Without normals the positions are the same.
      std::vector<float> positions_only(floats);
      workers.run(positions_only, {});
      EXPECT_EQ(positions_only, expected_positions);
    }
  }
}

}  // namespace
}  // namespace skinstream::server
