#include "core/deform/mesh_deformer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <stdexcept>

#include "core/deform/vertex_blend.h"
#include "tests/core/deform/deform_test_support.h"
#include "tests/support/allocation_counter.h"

namespace skinstream {
namespace {

using deform_test::deform_non_rigidly;
using deform_test::move_rigidly;
using deform_test::random_motion;
using deform_test::random_points;

// Two overlapping parts over 30 markers (part 0: markers 0-19, part 1: 10-29) and a detailed
// "mesh" of 200 vertices scattered over the same region, half of them blended between the parts.
struct TwoPartScene {
  SubjectModel subject;
  DeformationModel model;

  TwoPartScene() {
    std::mt19937_64 rng(3);
    const std::vector<Vec3> markers = random_points(rng, 30, Vec3(120, 80, 60));
    for (int i = 0; i < 30; ++i) {
      subject.marker_names.push_back("m" + std::to_string(i));
      subject.reference_positions.push_back(markers[i]);
    }
    model.part_names = {"a", "b"};
    for (int i = 0; i < 20; ++i) model.part_members.push_back({i, 1.0});
    model.part_member_offsets.push_back(20);
    for (int i = 10; i < 30; ++i) model.part_members.push_back({i, 1.0});
    model.part_member_offsets.push_back(40);
    model.reference_vertices = random_points(rng, 200, Vec3(110, 70, 50));
    for (int v = 0; v < 200; ++v) {
      if (v % 2 == 0) {
        model.vertex_influences.push_back({v % 4 == 0 ? 0 : 1, 1.0});
      } else {
        const double beta = 0.25 + 0.5 * (v % 7) / 6.0;
        model.vertex_influences.push_back({0, beta});
        model.vertex_influences.push_back({1, 1.0 - beta});
      }
      model.vertex_influence_offsets.push_back(static_cast<int>(model.vertex_influences.size()));
    }
    for (int f = 0; f + 2 < 200; f += 3) model.faces.push_back({f, f + 1, f + 2});
  }
};

std::vector<float> deform_all(MeshDeformer& deformer, const std::vector<Vec3>& markers, std::vector<float>* normals = nullptr) {
  std::vector<float> positions(static_cast<size_t>(deformer.vertex_count()) * 3);
  std::vector<float> unused;
  EXPECT_TRUE(deformer.deform(markers, positions, normals ? std::span<float>(*normals) : std::span<float>(unused)));
  return positions;
}

Vec3 vertex(const std::vector<float>& positions, int v) {
  return Vec3(positions[v * 3], positions[v * 3 + 1], positions[v * 3 + 2]);
}

TEST(MeshDeformer, RejectsModelInconsistentWithSubject) {
  TwoPartScene scene;
  scene.model.part_members[3].marker = 30;  // the subject has 30 markers
  EXPECT_THROW(MeshDeformer(scene.model, scene.subject), std::invalid_argument);
  TwoPartScene unnormalised;
  unnormalised.model.vertex_influences[0].weight = 0.5;
  EXPECT_THROW(MeshDeformer(unnormalised.model, unnormalised.subject), std::invalid_argument);
}

TEST(MeshDeformer, RejectsWrongMarkerCountAndMissingMarkersKeepingThePreviousFrame) {
  TwoPartScene scene;
  MeshDeformer deformer(scene.model, scene.subject);
  std::vector<float> positions(200 * 3), normals;
  std::vector<Vec3> markers = scene.subject.reference_positions;
  markers.pop_back();
  EXPECT_FALSE(deformer.solve_parts(markers));
  markers = scene.subject.reference_positions;
  markers[5] = missing_point();
  EXPECT_FALSE(deformer.solve_parts(markers));
  // Still the rest pose.
  deformer.deform_clusters(0, deformer.cluster_count());
  deformer.blend_vertices(0, 200, positions);
  for (int v = 0; v < 200; ++v) EXPECT_LT((vertex(positions, v) - scene.model.reference_vertices[v]).norm(), 1e-3);
}

TEST(MeshDeformer, RestPoseGivesReferenceVerticesInEveryMode) {
  TwoPartScene scene;
  for (DeformationMode mode : kDeformationModes) {
    MeshDeformer deformer(scene.model, scene.subject, mode);
    const std::vector<float> positions = deform_all(deformer, scene.subject.reference_positions);
    for (int v = 0; v < 200; ++v)
      EXPECT_LT((vertex(positions, v) - scene.model.reference_vertices[v]).norm(), 1e-3) << "vertex " << v;
  }
}

// Float evaluation against the double reference of eq. 8-9 (PartDeformer + blend_vertex).
TEST(MeshDeformer, MatchesThePerPartReferenceImplementation) {
  TwoPartScene scene;
  std::mt19937_64 rng(8);
  const std::vector<Vec3> now = deform_non_rigidly(scene.subject.reference_positions, random_motion(rng));
  for (DeformationMode mode : kDeformationModes) {
    MeshDeformer deformer(scene.model, scene.subject, mode);
    const std::vector<float> positions = deform_all(deformer, now);

    std::vector<PartDeformer> parts;
    for (int p = 0; p < 2; ++p) {
      std::vector<Vec3> reference, current;
      for (int k = scene.model.part_member_offsets[p]; k < scene.model.part_member_offsets[p + 1]; ++k) {
        reference.push_back(scene.subject.reference_positions[scene.model.part_members[k].marker]);
        current.push_back(now[scene.model.part_members[k].marker]);
      }
      parts.emplace_back(build_part_model(reference), mode);
      ASSERT_TRUE(parts.back().solve(current));
    }
    double worst = 0.0;
    for (int v = 0; v < 200; ++v) {
      const auto first = scene.model.vertex_influences.begin() + scene.model.vertex_influence_offsets[v];
      const auto last = scene.model.vertex_influences.begin() + scene.model.vertex_influence_offsets[v + 1];
      const std::vector<PartInfluence> influences(first, last);
      const Vec3 expected = blend_vertex(scene.model.reference_vertices[v], influences, parts);
      worst = std::max(worst, (vertex(positions, v) - expected).norm());
    }
    // Float arithmetic on coordinates of ~1000 mm: a few 1e-4 mm.
    EXPECT_LT(worst, 2e-3) << "mode " << static_cast<int>(mode);
    // The deformer's own parts (what eval-deform asks of single parts) are these fits.
    for (int p = 0; p < 2; ++p) {
      const Vec3 at = scene.model.reference_vertices[p * 100];
      const Vec3 own = deformer.part(p).deform(deformer.part(p).model().local_from_world(at));
      EXPECT_LT((own - parts[p].deform(parts[p].model().local_from_world(at))).norm(), 1e-9);
    }
    EXPECT_THROW(deformer.part(2), std::out_of_range);
  }
}

// A limb-like strip 1 m long with markers every 25 mm: sigma is ~100 mm, so most centres lie
// beyond the kernel's support from most vertices and the cluster stage leaves them out. The
// sums must still be eq. 8's over all centres (the double reference evaluates every one).
TEST(MeshDeformer, SupportCullingKeepsEveryNonZeroKernelTerm) {
  std::mt19937_64 rng(21);
  std::uniform_real_distribution<double> jitter(-4.0, 4.0);
  SubjectModel subject;
  DeformationModel model;
  model.part_names = {"strip"};
  for (int i = 0; i <= 40; ++i)
    for (int row = 0; row < 2; ++row) {
      const int index = static_cast<int>(subject.reference_positions.size());
      subject.marker_names.push_back("m" + std::to_string(index));
      subject.reference_positions.push_back(Vec3(25.0 * i, 30.0 * row + jitter(rng), 10.0 * ((i + row) % 2) + jitter(rng)));
      model.part_members.push_back({index, 1.0});
    }
  model.part_member_offsets.push_back(static_cast<int>(model.part_members.size()));
  model.reference_vertices = random_points(rng, 3000, Vec3(500, 20, 8), Vec3(500, 15, 5));
  for (int v = 0; v < 3000; ++v) {
    model.vertex_influences.push_back({0, 1.0});
    model.vertex_influence_offsets.push_back(v + 1);
  }
  for (int f = 0; f + 2 < 3000; f += 3) model.faces.push_back({f, f + 1, f + 2});

  const PartModel part_model = build_part_model(subject.reference_positions);
  long beyond = 0;
  for (const Vec3& v : model.reference_vertices)
    for (const Vec3& m : subject.reference_positions) beyond += (v - m).norm() > 3.0 * part_model.rbf_dilation;
  ASSERT_GT(beyond, 3000L * 82 / 2) << "the scene must put most centres out of reach";

  // Bend the strip (a few mm per 100 mm, more than the test of the small scene) and move it.
  std::vector<Vec3> now;
  const RigidTransform motion = random_motion(rng);
  for (const Vec3& p : subject.reference_positions)
    now.push_back(motion.apply(p + Vec3(0.0, 2e-5 * p.x() * p.x() + 3.0 * std::sin(p.x() / 60.0), 4.0 * std::cos(p.x() / 45.0))));
  MeshDeformer deformer(model, subject);
  ASSERT_GT(deformer.cluster_count(), 10);
  const std::vector<float> positions = deform_all(deformer, now);
  PartDeformer reference(part_model);
  ASSERT_TRUE(reference.solve(now));
  ASSERT_TRUE(reference.rbf_applied());
  double worst = 0.0, largest_rbf = 0.0;
  for (int v = 0; v < 3000; ++v) {
    const Vec3 expected = reference.deform(part_model.local_from_world(model.reference_vertices[v]));
    worst = std::max(worst, (vertex(positions, v) - expected).norm());
  }
  largest_rbf = reference.rbf_weights().cwiseAbs().maxCoeff();
  ASSERT_GT(largest_rbf, 0.1) << "the residual must be non-trivial for the comparison to mean something";
  EXPECT_LT(worst, 2e-3);
}

TEST(MeshDeformer, RigidMotionOfAllMarkersMovesTheMeshRigidly) {
  TwoPartScene scene;
  std::mt19937_64 rng(21);
  const RigidTransform motion = random_motion(rng);
  const std::vector<Vec3> moved = move_rigidly(scene.subject.reference_positions, motion);
  for (DeformationMode mode : kDeformationModes) {
    MeshDeformer deformer(scene.model, scene.subject, mode);
    const std::vector<float> positions = deform_all(deformer, moved);
    for (int v = 0; v < 200; ++v)
      EXPECT_LT((vertex(positions, v) - motion.apply(scene.model.reference_vertices[v])).norm(), 2e-3);
  }
}

TEST(MeshDeformer, FullMethodInterpolatesTheMarkersOfASinglePart) {
  // Vertices placed on the markers of a one-part model follow the markers exactly (RBF is an
  // interpolant at its centres), whatever the non-rigid motion.
  TwoPartScene scene;
  DeformationModel on_markers;
  on_markers.part_names = {"all"};
  for (int i = 0; i < 30; ++i) on_markers.part_members.push_back({i, 1.0});
  on_markers.part_member_offsets.push_back(30);
  on_markers.reference_vertices = scene.subject.reference_positions;
  for (int v = 0; v < 30; ++v) {
    on_markers.vertex_influences.push_back({0, 1.0});
    on_markers.vertex_influence_offsets.push_back(v + 1);
  }
  on_markers.faces = {{0, 1, 2}};
  std::mt19937_64 rng(5);
  const std::vector<Vec3> now = deform_non_rigidly(scene.subject.reference_positions, random_motion(rng));
  MeshDeformer deformer(on_markers, scene.subject, DeformationMode::QuadraticRbf);
  const std::vector<float> positions = deform_all(deformer, now);
  for (int v = 0; v < 30; ++v) EXPECT_LT((vertex(positions, v) - now[v]).norm(), 2e-3) << "marker " << v;
}

TEST(MeshDeformer, NormalsAreUnitAndFollowTheWinding) {
  SubjectModel subject;
  DeformationModel model;
  // A square in the z = 0 plane, counter-clockwise seen from +z, one part of its 4 corners.
  const std::vector<Vec3> corners = {Vec3(0, 0, 0), Vec3(100, 0, 0), Vec3(100, 100, 0), Vec3(0, 100, 0)};
  for (int i = 0; i < 4; ++i) {
    subject.marker_names.push_back("c" + std::to_string(i));
    subject.reference_positions.push_back(corners[i]);
    model.part_members.push_back({i, 1.0});
    model.vertex_influences.push_back({0, 1.0});
    model.vertex_influence_offsets.push_back(i + 1);
  }
  model.part_names = {"square"};
  model.part_member_offsets.push_back(4);
  model.reference_vertices = corners;
  model.faces = {{0, 1, 2}, {0, 2, 3}};
  MeshDeformer deformer(model, subject, DeformationMode::Rigid);
  std::vector<float> normals(12);
  deform_all(deformer, corners, &normals);
  for (int v = 0; v < 4; ++v) {
    EXPECT_NEAR(normals[v * 3 + 2], 1.0f, 1e-6f);
    EXPECT_NEAR(normals[v * 3], 0.0f, 1e-6f);
  }
}

// Against a double-precision sum of (b - a) x (c - a) over the faces around each vertex,
// computed from the deformed positions the deformer wrote, on a sheet whose vertices are shared
// by up to six faces and whose border vertices have open fans, plus faces that break the fans:
// a fin on an interior edge (three faces on one edge), one wound the other way and a lone
// triangle across the sheet.
TEST(MeshDeformer, NormalsAreTheAreaWeightedSumOfTheFacesAroundEachVertex) {
  deform_test::WavySheet sheet;
  sheet.model.faces.push_back({40, 71, 300});
  sheet.model.faces.push_back({500, 470, 501});
  sheet.model.faces.push_back({100, 650, 900});
  std::mt19937_64 rng(17);
  const std::vector<Vec3> now = deform_non_rigidly(sheet.subject.reference_positions, random_motion(rng));
  MeshDeformer deformer(sheet.model, sheet.subject);
  std::vector<float> normals(sheet.model.reference_vertices.size() * 3);
  const std::vector<float> positions = deform_all(deformer, now, &normals);
  std::vector<Vec3> expected(sheet.model.reference_vertices.size(), Vec3::Zero());
  for (const auto& f : sheet.model.faces) {
    const Vec3 a = vertex(positions, f[0]), b = vertex(positions, f[1]), c = vertex(positions, f[2]);
    for (int corner : f) expected[corner] += (b - a).cross(c - a);
  }
  double worst = 0.0;
  for (size_t v = 0; v < expected.size(); ++v) worst = std::max(worst, (vertex(normals, static_cast<int>(v)) - expected[v].normalized()).norm());
  EXPECT_LT(worst, 1e-5);
}

TEST(MeshDeformer, VertexAndNormalRangesComposeToTheWholeFrame) {
  TwoPartScene scene;
  std::mt19937_64 rng(9);
  const std::vector<Vec3> now = deform_non_rigidly(scene.subject.reference_positions, random_motion(rng));
  MeshDeformer whole(scene.model, scene.subject), split(scene.model, scene.subject);
  std::vector<float> normals_whole(600), normals_split(600), positions_split(600);
  const std::vector<float> positions_whole = deform_all(whole, now, &normals_whole);
  ASSERT_TRUE(split.solve_parts(now));
  const int clusters = split.cluster_count();
  ASSERT_GT(clusters, 1);
  split.deform_clusters(clusters / 2, clusters);
  split.deform_clusters(0, clusters / 2);
  split.blend_vertices(100, 200, positions_split);
  split.blend_vertices(0, 100, positions_split);
  split.vertex_normals(77, 200, positions_split, normals_split);
  split.vertex_normals(0, 77, positions_split, normals_split);
  EXPECT_EQ(positions_whole, positions_split);
  EXPECT_EQ(normals_whole, normals_split);
}

// Clusters never mix the two halves of the vertex sequence (DeformWorkers gives them to the
// threads that blend those halves), and a part's lower-half clusters come first.
TEST(MeshDeformer, ClustersKeepToOneHalfOfTheVertexSequence) {
  TwoPartScene scene;
  const MeshDeformer deformer(scene.model, scene.subject);
  // 200 vertices: three whole groups of 64 and a short one; the lower half is one whole group.
  ASSERT_EQ(deformer.normal_group_size(), 64);
  ASSERT_EQ(deformer.upper_half_slot(), 64);
  int influences[2][2] = {};  // [part][upper half]
  for (int slot = 0; slot < deformer.vertex_count(); ++slot) {
    const int v = deformer.sequence_vertex(slot);
    for (int k = scene.model.vertex_influence_offsets[v]; k < scene.model.vertex_influence_offsets[v + 1]; ++k)
      ++influences[scene.model.vertex_influences[k].part][slot >= deformer.upper_half_slot()];
  }
  std::vector<std::pair<int, bool>> expected;  // (part, upper half) per cluster
  for (int part = 0; part < 2; ++part)
    for (int half = 0; half < 2; ++half)
      for (int n = 0; n < (influences[part][half] + 63) / 64; ++n) expected.emplace_back(part, half == 1);
  ASSERT_EQ(deformer.cluster_count(), static_cast<int>(expected.size()));
  for (int c = 0; c < deformer.cluster_count(); ++c) {
    SCOPED_TRACE(c);
    EXPECT_EQ(deformer.cluster_part(c), expected[c].first);
    EXPECT_EQ(deformer.cluster_in_upper_half(c), expected[c].second);
  }
}

// A sheet of 8 rows of 64 vertices whose numbering alternates between its two ends (rows 0, 7,
// 1, 6, ...): halves of the numbering would interleave in space, and every row's edges to its
// neighbours would cross between threads. The sequence takes whole rows (groups of 64
// consecutive vertices) and cuts the sheet once, across its length.
TEST(MeshDeformer, TheVertexSequenceIsTwoSpatiallyCompactHalves) {
  TwoPartScene scene;
  constexpr int kRows = 8, kColumns = 64;
  const int row_of_block[kRows] = {0, 7, 1, 6, 2, 5, 3, 4};
  int block_of_row[kRows];
  for (int b = 0; b < kRows; ++b) block_of_row[row_of_block[b]] = b;
  DeformationModel& model = scene.model;
  model.reference_vertices.clear();
  model.vertex_influences.clear();
  model.vertex_influence_offsets.assign(1, 0);
  model.faces.clear();
  for (int b = 0; b < kRows; ++b)
    for (int c = 0; c < kColumns; ++c) {
      model.reference_vertices.emplace_back(2.0 * c - 60.0, 10.0 * row_of_block[b] - 35.0, 0.0);
      model.vertex_influences.push_back({0, 1.0});
      model.vertex_influence_offsets.push_back(static_cast<int>(model.vertex_influences.size()));
    }
  auto at = [&](int row, int column) { return block_of_row[row] * kColumns + column; };
  for (int r = 0; r + 1 < kRows; ++r)
    for (int c = 0; c + 1 < kColumns; ++c) {
      model.faces.push_back({at(r, c), at(r, c + 1), at(r + 1, c + 1)});
      model.faces.push_back({at(r, c), at(r + 1, c + 1), at(r + 1, c)});
    }
  const MeshDeformer deformer(model, scene.subject);
  ASSERT_EQ(deformer.upper_half_slot(), 4 * kColumns);
  std::vector<int> seen(model.reference_vertices.size(), 0);
  for (int slot = 0; slot < deformer.vertex_count(); ++slot) {
    SCOPED_TRACE(slot);
    const int v = deformer.sequence_vertex(slot);
    ASSERT_GE(v, 0);
    ASSERT_LT(v, deformer.vertex_count());
    ++seen[v];
    EXPECT_EQ(v % kColumns, slot % kColumns);  // whole groups of consecutive vertices
    EXPECT_EQ(model.reference_vertices[v].y() < 0.0, slot < deformer.upper_half_slot());  // rows 0-3 below
  }
  EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), deformer.vertex_count());  // a permutation
  EXPECT_THROW(deformer.sequence_vertex(deformer.vertex_count()), std::out_of_range);
  EXPECT_THROW(deformer.sequence_vertex(-1), std::out_of_range);
}

TEST(MeshDeformer, PerFrameWorkAllocatesNothing) {
  TwoPartScene scene;
  std::mt19937_64 rng(13);
  std::vector<std::vector<Vec3>> frames;
  for (int f = 0; f < 20; ++f) frames.push_back(deform_non_rigidly(scene.subject.reference_positions, random_motion(rng)));
  MeshDeformer deformer(scene.model, scene.subject);
  std::vector<float> positions(600), normals(600);
  test::CountAllocations count;
  for (const auto& markers : frames) ASSERT_TRUE(deformer.deform(markers, positions, normals));
  EXPECT_EQ(count.count(), 0u);
}

// Parts far larger than the small scene's (a trunk carries ~150 markers): dense solvers switch
// to blocked algorithms at such sizes, which must not allocate either.
TEST(MeshDeformer, PerFrameWorkAllocatesNothingWithLargeParts) {
  deform_test::WavySheet sheet(61);  // parts of ~300 markers
  ASSERT_GT(sheet.model.part_member_offsets[1], 140);
  std::mt19937_64 rng(14);
  std::vector<std::vector<Vec3>> frames;
  for (int f = 0; f < 10; ++f) frames.push_back(deform_non_rigidly(sheet.subject.reference_positions, random_motion(rng)));
  MeshDeformer deformer(sheet.model, sheet.subject);
  std::vector<float> positions(sheet.model.reference_vertices.size() * 3), normals(positions.size());
  ASSERT_TRUE(deformer.deform(frames[0], positions, normals));
  test::CountAllocations count;
  for (const auto& markers : frames) ASSERT_TRUE(deformer.deform(markers, positions, normals));
  EXPECT_EQ(count.count(), 0u);
}

}  // namespace
}  // namespace skinstream
