#include "protocol/files/subject_file.h"

#include <gtest/gtest.h>

#include <cmath>

#include <cstring>
#include <fstream>
#include <iterator>
#include <span>

#include "core/offline/subject_builder.h"
#include "protocol/byte_buffer.h"
#include "protocol/files/file_error.h"
#include "support/synthetic_limb.h"
#include "support/test_data.h"

namespace skinstream {
namespace {

// Every PCA model read back as written (the one-ring models and the regions' alike).
void expect_same_pca_models(const std::vector<MarkerPcaModel>& back, const std::vector<MarkerPcaModel>& written) {
  ASSERT_EQ(back.size(), written.size());
  for (size_t i = 0; i < back.size(); ++i) {
    EXPECT_EQ(back[i].mean, written[i].mean) << i;
    EXPECT_EQ(back[i].basis, written[i].basis) << i;
    EXPECT_EQ(back[i].variance, written[i].variance) << i;
    EXPECT_EQ(back[i].slot_calibration, written[i].slot_calibration) << i;
    EXPECT_EQ(back[i].rigid_variance, written[i].rigid_variance) << i;
    EXPECT_EQ(back[i].training_frames, written[i].training_frames) << i;
  }
}

std::vector<char> slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}
void spit(const std::string& path, const std::vector<char>& bytes) {
  std::ofstream(path, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}
std::string message_of(const std::string& path) {
  try {
    read_subject(path);
  } catch (const FileError& e) {
    return e.what();
  }
  return "";
}

class SubjectFile : public ::testing::Test {
 protected:
  void SetUp() override {
    model_ = build_subject(test::make_limb_capture(), {});
    path_ = test::scratch_path("limb.subject");
    write_subject(model_, path_);
  }
  SubjectModel model_;
  std::string path_;
};

TEST_F(SubjectFile, MissingFileIsAClearError) {
  EXPECT_NE(message_of(test::scratch_path("nope.subject")).find("cannot open"), std::string::npos);
}

TEST_F(SubjectFile, RejectsAnotherFormat) {
  const std::string other = test::scratch_path("other.subject");
  spit(other, std::vector<char>(100, 'x'));
  EXPECT_NE(message_of(other).find("bad magic"), std::string::npos);
}

TEST_F(SubjectFile, RejectsAnotherVersion) {
  std::vector<char> bytes = slurp(path_);
  bytes[8] = 99;  // version field
  const std::string other = test::scratch_path("v99.subject");
  spit(other, bytes);
  EXPECT_NE(message_of(other).find("version 99"), std::string::npos);
}

TEST_F(SubjectFile, RejectsATruncatedFile) {
  std::vector<char> bytes = slurp(path_);
  bytes.resize(bytes.size() / 2);
  const std::string cut = test::scratch_path("cut.subject");
  spit(cut, bytes);
  EXPECT_NE(message_of(cut).find("truncated"), std::string::npos);
}

TEST_F(SubjectFile, RejectsCorruptContent) {
  std::vector<char> bytes = slurp(path_);
  bytes[bytes.size() / 2] ^= 0x5A;
  const std::string bad = test::scratch_path("flipped.subject");
  spit(bad, bytes);
  EXPECT_NE(message_of(bad).find("CRC"), std::string::npos);
}

// Found by fuzzing (tests/fuzz/subject_file_fuzz.cpp, which gives an input of odd length the
// payload size and CRC a writer would, as done here): one-ring offsets 1.3 billion apart made
// the model check multiply the ring size by 3 in an int, past its range (undefined; the
// sanitizer builds stop on it). Refused now with the ring size, before it sizes anything.
TEST_F(SubjectFile, RingOffsetsFarApartAreRefusedWithoutOverflow) {
  std::vector<char> bytes = slurp(test::source_path("tests/protocol/fixtures/fuzz/subject_ring_offsets_overflow.sks"));
  ASSERT_GT(bytes.size(), 24u);
  const uint64_t payload = bytes.size() - 24;
  std::memcpy(bytes.data() + 12, &payload, 8);
  const uint32_t crc = crc32(reinterpret_cast<const unsigned char*>(bytes.data()) + 20, payload);
  std::memcpy(bytes.data() + bytes.size() - 4, &crc, 4);
  const std::string path = test::scratch_path("ring_offsets_overflow.sks");
  spit(path, bytes);
  const std::string message = message_of(path);
  EXPECT_NE(message.find("inconsistent subject model: marker"), std::string::npos) << message;
  EXPECT_NE(message.find("ring size -1335885824"), std::string::npos) << message;
}

TEST_F(SubjectFile, ReadsFromMemoryAsFromTheFile) {
  const std::vector<char> bytes = slurp(path_);
  const std::span<const unsigned char> view(reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size());
  const auto from_memory = read_subject_bytes(view, "limb.subject");
  EXPECT_EQ(from_memory.model.marker_names, model_.marker_names);
  EXPECT_EQ(from_memory.model.reference_positions, model_.reference_positions);
  EXPECT_EQ(from_memory.model.ring_offsets, model_.ring_offsets);
  try {
    read_subject_bytes(view.first(view.size() / 2), "limb.subject");
    ADD_FAILURE() << "half a file was read";
  } catch (const FileError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("limb.subject: truncated", 0), 0u) << e.what();
  }
}

TEST_F(SubjectFile, RefusesToWriteAnInconsistentModel) {
  SubjectModel broken = model_;
  broken.pca.pop_back();
  EXPECT_THROW(write_subject(broken, test::scratch_path("broken.subject")), FileError);
}

TEST_F(SubjectFile, RoundTripsExactly) {
  const SubjectModel back = read_subject(path_);
  EXPECT_EQ(back.marker_names, model_.marker_names);
  EXPECT_EQ(back.reference_positions, model_.reference_positions);
  EXPECT_EQ(back.triangles, model_.triangles);
  EXPECT_EQ(back.ring, model_.ring);
  EXPECT_EQ(back.ring_offsets, model_.ring_offsets);
  EXPECT_EQ(back.ring_local_reference, model_.ring_local_reference);
  EXPECT_EQ(back.anchors, model_.anchors);
  expect_same_pca_models(back.pca, model_.pca);
  EXPECT_EQ(back.parameters.alpha1, model_.parameters.alpha1);
}

}  // namespace
}  // namespace skinstream

namespace skinstream {
namespace {

// A small deformation model over the limb subject: one part of all markers, the mesh = the
// markers themselves (vertex i on marker i), one triangle.
DeformationModel limb_deformation(const SubjectModel& model) {
  DeformationModel d;
  d.reference_vertices = model.reference_positions;
  d.faces = {{0, 1, 2}};
  d.part_names = {"limb"};
  for (int i = 0; i < model.marker_count(); ++i) d.part_members.push_back({i, 1.0});
  d.part_member_offsets.push_back(model.marker_count());
  for (int v = 0; v < model.marker_count(); ++v) {
    d.vertex_influences.push_back({0, 1.0});
    d.vertex_influence_offsets.push_back(v + 1);
  }
  d.registration_rms_mm = 0.25;
  d.part_rbf_ridge = {0.0316};
  d.part_quadratic_ridge = {3.16};
  return d;
}

TEST_F(SubjectFile, DeformationModelRoundTripsExactly) {
  const DeformationModel d = limb_deformation(model_);
  const std::string path = test::scratch_path("limb_mesh.subject");
  write_subject(model_, &d, path);
  const auto back = read_subject_file(path);
  ASSERT_TRUE(back.deformation.has_value());
  EXPECT_EQ(back.deformation->reference_vertices, d.reference_vertices);
  EXPECT_EQ(back.deformation->faces, d.faces);
  EXPECT_EQ(back.deformation->part_names, d.part_names);
  EXPECT_EQ(back.deformation->part_member_offsets, d.part_member_offsets);
  EXPECT_EQ(back.deformation->vertex_influence_offsets, d.vertex_influence_offsets);
  EXPECT_EQ(back.deformation->registration_rms_mm, 0.25);
  EXPECT_EQ(back.deformation->part_rbf_ridge, d.part_rbf_ridge);
  EXPECT_EQ(back.deformation->part_quadratic_ridge, d.part_quadratic_ridge);
  EXPECT_EQ(back.model.marker_names, model_.marker_names);
  // Without a mesh: no deformation model, and read_subject still gives the markers.
  EXPECT_FALSE(read_subject_file(path_).deformation.has_value());
  EXPECT_EQ(read_subject(path).marker_names, model_.marker_names);
}

// A sparse set's fitted body: the skeleton, each part's quadratic flag and the rest vertices.
DeformationModel fitted_deformation(const SubjectModel& model) {
  DeformationModel d = limb_deformation(model);
  d.skeleton.segments = {{"pelvis", -1, Vec3(0, 0, 900)}, {"thigh", 0, Vec3(100, 0, 850)}};
  for (int i = 0; i < model.marker_count(); ++i) {
    if (i % 2) d.skeleton.marker_weights.push_back({1, 1.0});
    else d.skeleton.marker_weights.insert(d.skeleton.marker_weights.end(), {{0, 0.25}, {1, 0.75}});
    d.skeleton.marker_weight_offsets.push_back(static_cast<int>(d.skeleton.marker_weights.size()));
  }
  d.skeleton.part_segment = {1};
  d.part_quadratic = {0};
  d.rest_vertices = d.reference_vertices;
  for (Vec3& v : d.rest_vertices) v += Vec3(1.5, -2.0, 0.25);
  return d;
}

TEST_F(SubjectFile, FittedBodyRoundTripsExactly) {
  const DeformationModel d = fitted_deformation(model_);
  const std::string path = test::scratch_path("limb_fitted.subject");
  write_subject(model_, &d, path);
  const auto back = read_subject_file(path);
  ASSERT_TRUE(back.deformation.has_value());
  const SegmentSkeleton& s = back.deformation->skeleton;
  ASSERT_EQ(s.segment_count(), 2);
  EXPECT_EQ(s.segments[1].name, "thigh");
  EXPECT_EQ(s.segments[1].parent, 0);
  EXPECT_EQ(s.segments[1].pivot, Vec3(100, 0, 850));
  EXPECT_EQ(s.marker_weight_offsets, d.skeleton.marker_weight_offsets);
  ASSERT_EQ(s.marker_weights.size(), d.skeleton.marker_weights.size());
  for (size_t k = 0; k < s.marker_weights.size(); ++k) {
    EXPECT_EQ(s.marker_weights[k].segment, d.skeleton.marker_weights[k].segment);
    EXPECT_EQ(s.marker_weights[k].weight, d.skeleton.marker_weights[k].weight);
  }
  EXPECT_EQ(s.part_segment, d.skeleton.part_segment);
  EXPECT_EQ(back.deformation->part_quadratic, d.part_quadratic);
  EXPECT_EQ(back.deformation->rest_vertices, d.rest_vertices);
}

// A fitted body whose skeleton does not add up is refused when written and when read.
TEST_F(SubjectFile, RefusesAFittedBodyWithBrokenWeights) {
  DeformationModel d = limb_deformation(model_);
  d.skeleton.segments = {{"pelvis", -1, Vec3(0, 0, 900)}};
  for (int i = 0; i < model_.marker_count(); ++i) {
    d.skeleton.marker_weights.push_back({0, i == 0 ? 0.5 : 1.0});  // marker 0 sums to 0.5
    d.skeleton.marker_weight_offsets.push_back(i + 1);
  }
  d.skeleton.part_segment = {0};
  EXPECT_THROW(write_subject(model_, &d, test::scratch_path("limb_bad_skeleton.subject")), FileError);
}

// Rewrites a file written now as an older version: drops the last `dropped` bytes before the
// CRC (the fields that version lacks, all at the end of the deformation section), then mends
// the version, the size and the CRC.
void make_older(const std::string& path, uint32_t version, size_t dropped) {
  std::vector<char> bytes = slurp(path);
  bytes.erase(bytes.end() - 4 - static_cast<std::ptrdiff_t>(dropped), bytes.end() - 4);
  std::memcpy(bytes.data() + 8, &version, 4);
  uint64_t size = 0;
  std::memcpy(&size, bytes.data() + 12, 8);
  size -= dropped;
  std::memcpy(bytes.data() + 12, &size, 8);
  const uint32_t crc = crc32(reinterpret_cast<const unsigned char*>(bytes.data()) + 20, size);
  std::memcpy(bytes.data() + bytes.size() - 4, &crc, 4);
  spit(path, bytes);
}

SubjectModel without_regions(SubjectModel model) {
  model.region_offsets.clear();
  model.region.clear();
  model.region_pca.clear();
  return model;
}

// The regions and their PCA models are read back as written.
TEST_F(SubjectFile, RegionsRoundTrip) {
  ASSERT_TRUE(model_.has_regions());
  const SubjectModel back = read_subject(path_);
  EXPECT_EQ(back.region_offsets, model_.region_offsets);
  EXPECT_EQ(back.region, model_.region);
  expect_same_pca_models(back.region_pca, model_.region_pca);
}

// A version 4 file (before the regions) reads with none: the filler then has no regional opinion.
TEST_F(SubjectFile, VersionFourFileReadsWithoutRegions) {
  const std::string path = test::scratch_path("limb_v4.subject");
  write_subject(without_regions(model_), path);
  make_older(path, 4, 4 + 1);  // the region count (0), the fitted body's flag (0)
  const SubjectModel back = read_subject(path);
  EXPECT_FALSE(back.has_regions());
  EXPECT_EQ(back.validate(), "");
  EXPECT_EQ(back.ring, model_.ring);
}

// A version 2 file (before the per-part ridges): the same layout without the two ridge counts at
// the end of the deformation section. It still reads, with no ridges (0 for every part).
TEST_F(SubjectFile, VersionTwoFileReadsWithoutRidges) {
  DeformationModel d = limb_deformation(model_);
  d.part_rbf_ridge.clear();
  d.part_quadratic_ridge.clear();
  const std::string path = test::scratch_path("limb_v2.subject");
  write_subject(without_regions(model_), &d, path);
  make_older(path, 2, 8 + 4 + 1);  // the two ridge counts (0 each), the region count (0), the fitted body's flag (0)
  const auto back = read_subject_file(path);
  ASSERT_TRUE(back.deformation.has_value());
  EXPECT_TRUE(back.deformation->part_rbf_ridge.empty());
  EXPECT_TRUE(back.deformation->part_quadratic_ridge.empty());
  EXPECT_EQ(back.deformation->registration_rms_mm, 0.25);
  EXPECT_EQ(back.deformation->validate(model_.marker_count()), "");
}

// A version 3 file (eq. 7's ridges, before eq. 6's): reads with no quadratic ridges, which
// means the paper's exact fit for every part.
TEST_F(SubjectFile, VersionThreeFileReadsWithoutQuadraticRidges) {
  DeformationModel d = limb_deformation(model_);
  d.part_quadratic_ridge.clear();
  const std::string path = test::scratch_path("limb_v3.subject");
  write_subject(without_regions(model_), &d, path);
  make_older(path, 3, 4 + 4 + 1);  // the quadratic ridge count (0), the region count (0), the fitted body's flag (0)
  const auto back = read_subject_file(path);
  ASSERT_TRUE(back.deformation.has_value());
  EXPECT_EQ(back.deformation->part_rbf_ridge, d.part_rbf_ridge);
  EXPECT_TRUE(back.deformation->part_quadratic_ridge.empty());
  EXPECT_EQ(back.deformation->validate(model_.marker_count()), "");
}

TEST_F(SubjectFile, RefusesToWriteADeformationModelOfAnotherSubject) {
  DeformationModel d = limb_deformation(model_);
  d.part_members.back().marker = model_.marker_count() + 5;  // a marker this subject lacks
  try {
    write_subject(model_, &d, test::scratch_path("mismatch.subject"));
    FAIL() << "wrote a mismatched deformation model";
  } catch (const FileError& e) {
    EXPECT_NE(std::string(e.what()).find("part member marker"), std::string::npos) << e.what();
  }
  for (const std::vector<double>& ridges : {std::vector<double>{0.1, 0.2}, std::vector<double>{-0.1}}) {
    DeformationModel bad_ridges = limb_deformation(model_);
    bad_ridges.part_rbf_ridge = ridges;  // two for one part; a negative one
    try {
      write_subject(model_, &bad_ridges, test::scratch_path("ridges.subject"));
      FAIL() << "wrote unusable ridges";
    } catch (const FileError& e) {
      EXPECT_NE(std::string(e.what()).find("ridge"), std::string::npos) << e.what();
    }
    DeformationModel bad_quadratic = limb_deformation(model_);
    bad_quadratic.part_quadratic_ridge = ridges;
    try {
      write_subject(model_, &bad_quadratic, test::scratch_path("quadratic_ridges.subject"));
      FAIL() << "wrote unusable quadratic ridges";
    } catch (const FileError& e) {
      EXPECT_NE(std::string(e.what()).find("quadratic ridge"), std::string::npos) << e.what();
    }
  }
}

TEST_F(SubjectFile, CorruptDeformationSectionIsRejected) {
  const DeformationModel d = limb_deformation(model_);
  const std::string path = test::scratch_path("limb_mesh_corrupt.subject");
  write_subject(model_, &d, path);
  std::vector<char> bytes = slurp(path);
  // Truncated inside the deformation section (the header's size no longer matches).
  std::vector<char> cut(bytes.begin(), bytes.end() - 40);
  spit(path, cut);
  EXPECT_NE(message_of(path).find("truncated"), std::string::npos) << message_of(path);
  // A flipped byte inside the deformation section: the CRC catches it.
  bytes[bytes.size() - 60] ^= 0x5a;
  spit(path, bytes);
  EXPECT_NE(message_of(path).find("CRC"), std::string::npos) << message_of(path);
}

// Values the model's shape check lets through, written as they are and refused on reading, each
// with what is wrong: NaN and 1e300 went into the filler (and non-finite markers were published),
// duplicate names and names with control characters into the matching and the logs.
TEST_F(SubjectFile, EveryValueReadIsChecked) {
  const std::string path = test::scratch_path("bad_values.subject");
  auto refusal = [&](const SubjectModel& model, const DeformationModel* deformation = nullptr) {
    write_subject(model, deformation, path);
    return message_of(path);
  };
  SubjectModel m = model_;
  m.reference_positions[0].x() = 1e300;
  EXPECT_NE(refusal(m).find("bad value: marker 0's reference position is not finite or beyond 1 km"), std::string::npos) << refusal(m);
  m = model_;
  m.local_reference_frames[1](0, 0) = std::nan("");
  EXPECT_NE(refusal(m).find("marker 1's local reference frame is not a rotation"), std::string::npos) << refusal(m);
  m = model_;
  m.ring_local_reference[0] = Vec3(0, 0, 1e300);
  EXPECT_NE(refusal(m).find("a one-ring member's local position is not finite"), std::string::npos) << refusal(m);
  m = model_;
  m.parameters.alpha1 = std::nan("");
  EXPECT_NE(refusal(m).find("alpha1 and alpha2 must be in (0, 10]"), std::string::npos) << refusal(m);
  m = model_;
  m.pca[2].basis(0, 0) = 1e300;
  EXPECT_NE(refusal(m).find("marker 2's PCA model has a basis value outside [-1, 1]"), std::string::npos) << refusal(m);
  m = model_;
  m.marker_names[2] = m.marker_names[0];
  EXPECT_NE(refusal(m).find("marker 2's name '" + m.marker_names[0] + "' is another marker's too"), std::string::npos) << refusal(m);
  m = model_;
  m.marker_names[1] = "LFH\x1b[31mD";
  EXPECT_NE(refusal(m).find("marker 1's name is empty, longer than 256 bytes or holds a control character"), std::string::npos)
      << refusal(m);
  DeformationModel d = limb_deformation(model_);
  d.reference_vertices[0] = Vec3(1e300, 0, 0);
  EXPECT_NE(refusal(model_, &d).find("a mesh vertex is not finite or beyond 1 km"), std::string::npos) << refusal(model_, &d);
  d = limb_deformation(model_);
  d.part_names[0] = "arm\x07";
  EXPECT_NE(refusal(model_, &d).find("a part's name is empty, longer than 256 bytes or holds a control character"), std::string::npos)
      << refusal(model_, &d);
  d = fitted_deformation(model_);
  d.rest_vertices[3] = Vec3(0, 2e6, 0);
  EXPECT_NE(refusal(model_, &d).find("a rest-pose vertex is not finite or beyond 1 km"), std::string::npos) << refusal(model_, &d);
  d = fitted_deformation(model_);
  d.skeleton.segments[1].pivot.z() = 1e300;
  EXPECT_NE(refusal(model_, &d).find("skeleton segment 'thigh''s joint is not finite"), std::string::npos) << refusal(model_, &d);
  // The model as built reads back.
  write_subject(model_, path);
  EXPECT_NO_THROW(read_subject_file(path));
}

}  // namespace
}  // namespace skinstream
