#include "server/pipeline/deform_workers.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <random>
#include <set>
#include <string>
#include <thread>

#include "server/pipeline/deform_cpus.h"
#include "support/thread_names.h"
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
  for (int threads : {1, 2, 4}) {  // 4 threads on a 2-core machine: workers are often late
    MeshDeformer deformer(sheet.model, sheet.subject);
    DeformWorkers workers(deformer, threads);
    EXPECT_EQ(workers.threads(), threads);
    std::mt19937_64 rng(4);
    for (int frame = 0; frame < 30; ++frame) {
      const std::vector<Vec3> now =
          deform_test::deform_non_rigidly(sheet.subject.reference_positions, deform_test::random_motion(rng));
      std::vector<float> positions(floats), normals(floats), expected_positions(floats), expected_normals(floats);
      ASSERT_TRUE(reference.deform(now, expected_positions, expected_normals));
      ASSERT_TRUE(workers.run(now, positions, normals));
      EXPECT_EQ(positions, expected_positions) << threads << " threads, frame " << frame;
      EXPECT_EQ(normals, expected_normals) << threads << " threads, frame " << frame;
      // Without normals the positions are the same.
      std::vector<float> positions_only(floats);
      ASSERT_TRUE(workers.run(now, positions_only, {}));
      EXPECT_EQ(positions_only, expected_positions);
    }
  }
}

// Frames at an uneven pace, threads pinned (when the machine has two CPUs) and anticipating
// each frame: they sleep until the spin lead before it is due, or come late when a frame is
// early; either way every frame is the single-thread frame, and stopping does not hang.
TEST(DeformWorkers, PinnedAnticipatingWorkersGiveTheSameFramesAtAnyPace) {
  deform_test::WavySheet sheet;
  const size_t floats = sheet.model.reference_vertices.size() * 3;
  MeshDeformer reference(sheet.model, sheet.subject);
  MeshDeformer deformer(sheet.model, sheet.subject);
  DeformWorkerOptions options;
  options.threads = 2;
  options.spin_lead = std::chrono::microseconds(1000);
  const std::vector<int> allowed = allowed_cpus();
  if (allowed.size() >= 2) options.cpus = {allowed[allowed.size() - 2], allowed.back()};
  if (!options.cpus.empty()) {
    EXPECT_TRUE(pin_this_thread(options.cpus[0]));
  }
  {
    DeformWorkers workers(deformer, options);
    EXPECT_EQ(workers.unpinned_workers(), 0);
    std::mt19937_64 rng(5);
    const int gaps_us[] = {4000, 4000, 4000, 0, 9000, 300, 4000, 20000, 4000, 1000};
    for (int frame = 0; frame < 40; ++frame) {
      std::this_thread::sleep_for(std::chrono::microseconds(gaps_us[frame % 10]));
      const std::vector<Vec3> now =
          deform_test::deform_non_rigidly(sheet.subject.reference_positions, deform_test::random_motion(rng));
      std::vector<float> positions(floats), normals(floats), expected_positions(floats), expected_normals(floats);
      ASSERT_TRUE(reference.deform(now, expected_positions, expected_normals));
      if (frame % 3 == 0) workers.get_ready();
      ASSERT_TRUE(workers.run(now, positions, normals));
      EXPECT_EQ(positions, expected_positions) << "frame " << frame;
      EXPECT_EQ(normals, expected_normals) << "frame " << frame;
    }
  }  // joins a worker that may be asleep until the next frame it expected
  set_this_thread_cpus(allowed);  // the test thread as it was
}

// Each worker names itself deform-N (N from 1; the calling thread is 0), as `top -H` shows.
TEST(DeformWorkers, WorkersNameThemselves) {
  deform_test::WavySheet sheet;
  MeshDeformer deformer(sheet.model, sheet.subject);
  DeformWorkers workers(deformer, 3);
  // Each worker names itself once it runs.
  std::multiset<std::string> names = test::process_thread_names();
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while ((names.count("deform-1") == 0 || names.count("deform-2") == 0) && std::chrono::steady_clock::now() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    names = test::process_thread_names();
  }
  EXPECT_EQ(names.count("deform-1"), 1u);
  EXPECT_EQ(names.count("deform-2"), 1u);
}

TEST(DeformWorkers, RejectsUnusableMarkersAndKeepsThePreviousFit) {
  deform_test::WavySheet sheet;
  const size_t floats = sheet.model.reference_vertices.size() * 3;
  MeshDeformer deformer(sheet.model, sheet.subject);
  DeformWorkers workers(deformer, 2);
  std::mt19937_64 rng(6);
  const std::vector<Vec3> now =
      deform_test::deform_non_rigidly(sheet.subject.reference_positions, deform_test::random_motion(rng));
  std::vector<float> fitted(floats), again(floats);
  ASSERT_TRUE(workers.run(now, fitted, {}));
  std::vector<Vec3> short_by_one(now.begin(), now.end() - 1), with_nan = now;
  with_nan[7].x() = std::nan("");
  EXPECT_FALSE(workers.run(short_by_one, again, {}));
  EXPECT_FALSE(workers.run(with_nan, again, {}));
  // The deformer still holds the last good fit: its stages reproduce that frame.
  deformer.deform_clusters(0, deformer.cluster_count());
  deformer.blend_vertices(0, deformer.vertex_count(), again);
  EXPECT_EQ(again, fitted);
}

}  // namespace
}  // namespace skinstream::server
