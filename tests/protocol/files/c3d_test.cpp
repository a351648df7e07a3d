// C3D reading and writing against the real shared captures. Expected counts were measured by
// decoding the files independently (a short Python reader of the header, parameters and data).
#include "protocol/files/c3d.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <map>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "protocol/files/file_error.h"
#include "support/capture_assertions.h"
#include "support/file_error_assertion.h"
#include "support/test_data.h"

namespace skinstream {
namespace {

using test::scratch_path;

std::string capture_path(const std::string& relative) {
  return test::shared_path("data/captures/" + relative);
}

using Bytes = std::vector<char>;

Bytes read_file_chars(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(in), {});
}

void write_file_chars(const std::string& path, const Bytes& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

uint16_t get_u16(const Bytes& b, size_t at) {
  return static_cast<uint8_t>(b[at]) | static_cast<uint8_t>(b[at + 1]) << 8;
}
void put_u16(Bytes& b, size_t at, uint16_t v) {
  b[at] = static_cast<char>(v & 0xFF);
  b[at + 1] = static_cast<char>(v >> 8);
}
void put_f32(Bytes& b, size_t at, float v) { std::memcpy(&b[at], &v, 4); }

// Where a parameter lies in a well-formed Intel file, for surgery on test copies.
struct ParameterLocation {
  size_t type = 0;  // the data type byte; dimension count follows, then dimensions
  size_t data = 0;
};

ParameterLocation locate(const Bytes& b, const std::string& group, const std::string& name) {
  size_t at = (static_cast<uint8_t>(b[0]) - 1) * 512 + 4;
  std::map<int, std::string> groups;
  std::vector<std::pair<int, std::pair<std::string, ParameterLocation>>> parameters;
  for (;;) {
    const int length = std::abs(static_cast<int8_t>(b[at]));
    const int id = static_cast<int8_t>(b[at + 1]);
    if (length == 0) break;
    const std::string record_name(&b[at + 2], length);
    const size_t link_at = at + 2 + length;
    if (id < 0) {
      groups[-id] = record_name;
    } else {
      const size_t type_at = link_at + 2;
      parameters.push_back(
          {id, {record_name, {type_at, type_at + 2 + static_cast<uint8_t>(b[type_at + 1])}}});
    }
    const uint16_t link = get_u16(b, link_at);
    if (link == 0) break;
    at = link_at + link;
  }
  for (const auto& [id, entry] : parameters)
    if (groups[id] == group && entry.first == name) return entry.second;
  ADD_FAILURE() << "no parameter " << group << ":" << name;
  return {};
}

using test::expect_same_capture;
using test::missing_mask;
using test::throws_file_error;

// A patched copy of a shared capture in the scratch folder; returns its path.
template <typename Patch>
std::string patched_copy(const std::string& source, const std::string& name, Patch&& patch) {
  Bytes bytes = read_file_chars(capture_path(source));
  patch(bytes);
  const std::string path = scratch_path(name);
  write_file_chars(path, bytes);
  return path;
}

std::string truncated_copy(const std::string& source, size_t size) {
  return patched_copy(source, "c3d_truncated_" + std::to_string(size) + ".c3d",
                      [&](Bytes& b) { b.resize(size); });
}


size_t missing_count(const Capture& c) {
  const auto mask = missing_mask(c);
  return static_cast<size_t>(std::count(mask.begin(), mask.end(), true));
}

double max_abs_coordinate(const Capture& c) {
  double largest = 0.0;
  for (const Vec3& p : c.positions)
    if (is_present(p)) largest = std::max(largest, p.cwiseAbs().maxCoeff());
  return largest;
}


void expect_point(const Capture& c, int frame, int point, const Vec3& expected) {
  ASSERT_TRUE(c.present(frame, point));
  EXPECT_NEAR(c.at(frame, point).x(), expected.x(), 1e-3);
  EXPECT_NEAR(c.at(frame, point).y(), expected.y(), 1e-3);
  EXPECT_NEAR(c.at(frame, point).z(), expected.z(), 1e-3);
}

const char* const kSample01 = "c3d-org/sample01/Eb015pi.c3d";  // Intel, integer storage

// ---------------------------------------------------------------- invalid input

TEST(C3dInvalid, MissingFileNamesTheFile) {
  const std::string path = scratch_path("no_such_capture.c3d");
  EXPECT_TRUE(throws_file_error([&] { read_c3d(path); }, path, "no such file"));
}

TEST(C3dInvalid, TruncatedCopiesOfARealFileAreRejected) {
  // Eb015pi: parameter section blocks 2-10 (bytes 512-5119), data from byte 5120,
  // 450 frames x (26 points x 4 + 64 analog words) x 2 bytes = 151200 bytes: ends at 156320.
  for (size_t size : {0, 100, 511, 512, 600, 5119, 5120, 80000, 156319}) {
    SCOPED_TRACE(size);
    const std::string path = truncated_copy(kSample01, size);
    EXPECT_TRUE(throws_file_error([&] { read_c3d(path); }, path, "truncated"));
  }
  // Cut exactly at the end of the data (dropping only the block padding): still complete.
  const Capture whole = read_c3d(truncated_copy(kSample01, 156320));
  EXPECT_EQ(whole.frame_count, 450);
}

TEST(C3dInvalid, TruncatedFloatFileIsRejected) {
  // Eb015pr: float storage doubles the frame size: data ends at 5120 + 450 x 336 x 2 = 307520.
  const std::string path = truncated_copy("c3d-org/sample01/Eb015pr.c3d", 307519);
  EXPECT_TRUE(throws_file_error([&] { read_c3d(path); }, path, "truncated: parameters say 450 frames"));
}

TEST(C3dInvalid, BadParameterBlockPointer) {
  for (int pointer : {0, 1}) {
    const std::string path = patched_copy(kSample01, "c3d_pointer_" + std::to_string(pointer) + ".c3d",
                                          [&](Bytes& b) { b[0] = static_cast<char>(pointer); });
    EXPECT_TRUE(throws_file_error([&] { read_c3d(path); }, path, "bad parameter block pointer"));
  }
  // sample02 pc_int is 85 blocks long: block 200 lies past its end.
  const std::string past_end = patched_copy("c3d-org/sample02/pc_int.c3d", "c3d_pointer_200.c3d",
                                            [](Bytes& b) { b[0] = static_cast<char>(200); });
  EXPECT_TRUE(throws_file_error([&] { read_c3d(past_end); }, past_end, "bad parameter block pointer 200"));
  // Pointing into the middle of the parameters: whatever is found there must be refused cleanly.
  const std::string inside = patched_copy(kSample01, "c3d_pointer_5.c3d", [](Bytes& b) { b[0] = 5; });
  EXPECT_TRUE(throws_file_error([&] { read_c3d(inside); }, inside, ""));
}

TEST(C3dInvalid, NotAC3dFile) {
  const std::string path = patched_copy(kSample01, "c3d_bad_key.c3d", [](Bytes& b) { b[1] = 0x51; });
  EXPECT_TRUE(throws_file_error([&] { read_c3d(path); }, path, "not a C3D file"));
}

TEST(C3dInvalid, UnknownProcessorType) {
  const std::string path = patched_copy(kSample01, "c3d_processor_99.c3d", [](Bytes& b) { b[512 + 3] = 99; });
  EXPECT_TRUE(throws_file_error([&] { read_c3d(path); }, path, "unknown processor type 99"));
}

TEST(C3dInvalid, ZeroOrNegativeRate) {
  for (float rate : {0.0f, -50.0f}) {
    const std::string path = patched_copy(
        kSample01, "c3d_rate.c3d", [&](Bytes& b) { put_f32(b, locate(b, "POINT", "RATE").data, rate); });
    EXPECT_TRUE(throws_file_error([&] { read_c3d(path); }, path, "bad frame rate"));
  }
}

TEST(C3dInvalid, FewerLabelsThanPoints) {
  // POINT:LABELS is a 4 x 48 array; claim 20 labels for the 26 points.
  const std::string fewer = patched_copy(kSample01, "c3d_labels_20.c3d",
                                         [](Bytes& b) { b[locate(b, "POINT", "LABELS").type + 3] = 20; });
  EXPECT_TRUE(
      throws_file_error([&] { read_c3d(fewer); }, fewer, "POINT:LABELS holds 20 labels for 26 points"));
  const std::string more_points = patched_copy(
      kSample01, "c3d_used_49.c3d", [](Bytes& b) { put_u16(b, locate(b, "POINT", "USED").data, 49); });
  EXPECT_TRUE(
      throws_file_error([&] { read_c3d(more_points); }, more_points, "holds 48 labels for 49 points"));
}

TEST(C3dInvalid, CorruptParameterRecords) {
  const std::string bad_type =
      patched_copy(kSample01, "c3d_bad_type.c3d", [](Bytes& b) { b[locate(b, "POINT", "USED").type] = 3; });
  EXPECT_TRUE(throws_file_error([&] { read_c3d(bad_type); }, bad_type, "data type 3"));
  // 255 x 255 characters cannot fit in the 9-block section.
  const std::string oversized = patched_copy(kSample01, "c3d_oversized.c3d", [](Bytes& b) {
    const size_t type = locate(b, "POINT", "LABELS").type;
    b[type + 2] = static_cast<char>(255);
    b[type + 3] = static_cast<char>(255);
  });
  EXPECT_TRUE(throws_file_error([&] { read_c3d(oversized); }, oversized, "runs past the parameter section"));
}

TEST(C3dInvalid, DataStartInsideParameters) {
  const std::string path = patched_copy(kSample01, "c3d_data_start.c3d", [](Bytes& b) {
    put_u16(b, locate(b, "POINT", "DATA_START").data, 3);
  });
  EXPECT_TRUE(throws_file_error([&] { read_c3d(path); }, path, "data start block 3"));
}

TEST(C3dInvalid, AnalogLayoutDisagreement) {
  // 15 channels x 4 samples = 60 analog words, the header says 64: the frame size is unknowable.
  const std::string path = patched_copy(kSample01, "c3d_analog.c3d",
                                        [](Bytes& b) { put_u16(b, locate(b, "ANALOG", "USED").data, 15); });
  EXPECT_TRUE(throws_file_error([&] { read_c3d(path); }, path, "analog samples per frame"));
}

TEST(C3dInvalid, UnknownUnits) {
  const std::string path = patched_copy(kSample01, "c3d_units.c3d", [](Bytes& b) {
    std::memcpy(&b[locate(b, "POINT", "UNITS").data], "ft  ", 4);
  });
  EXPECT_TRUE(throws_file_error([&] { read_c3d(path); }, path, "unknown POINT:UNITS 'ft'"));
}

TEST(C3dInvalid, RandomDamageEndsInFileErrorOrAValidCapture) {
  // Damage to header and parameters must never crash or throw anything but FileError.
  const Bytes original = read_file_chars(capture_path(kSample01));
  std::mt19937 random(20240611);
  const std::string path = scratch_path("c3d_fuzz.c3d");
  int refused = 0;
  for (int trial = 0; trial < 400; ++trial) {
    Bytes bytes = original;
    const int changes = 1 + static_cast<int>(random() % 4);
    for (int i = 0; i < changes; ++i) bytes[random() % 5120] = static_cast<char>(random());
    if (trial % 4 == 0) bytes.resize(random() % bytes.size());
    write_file_chars(path, bytes);
    try {
      const Capture c = read_c3d(path);
      EXPECT_EQ(c.positions.size(), static_cast<size_t>(c.frame_count) * c.labels.size());
    } catch (const FileError&) {
      ++refused;
    } catch (const std::exception& e) {
      ADD_FAILURE() << "trial " << trial << ": non-FileError " << e.what();
    }
  }
  EXPECT_GT(refused, 0);
}

// ---------------------------------------------------------------- from memory

std::span<const uint8_t> as_span(const Bytes& bytes) { return {reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size()}; }

TEST(C3dFromMemory, ReadsEveryEncodingAsTheFileReaderDoes) {
  // Integer and float storage, Intel, DEC and MIPS (sample01), analog samples between frames
  // (Sample_Jump2), metres and gaps (basket sprint) and a long take (CMU 85_02).
  for (const std::string file : {"c3d-org/sample01/Eb015pi.c3d", "c3d-org/sample01/Eb015pr.c3d", "c3d-org/sample01/Eb015vi.c3d",
                                 "c3d-org/sample01/Eb015vr.c3d", "c3d-org/sample01/Eb015si.c3d", "c3d-org/sample01/Eb015sr.c3d",
                                 "c3d-org/Sample_Jump2.c3d", "kineticstoolkit/kinematics_basket_sprint.c3d", "cmu/85_02.c3d"}) {
    SCOPED_TRACE(file);
    const Capture from_file = read_c3d(capture_path(file));
    ASSERT_GT(from_file.frame_count, 0);
    expect_same_capture(from_file, read_c3d_bytes(as_span(read_file_chars(capture_path(file))), file), 0.0);
  }
}

TEST(C3dFromMemory, TruncatedBytesAreRefusedUnderTheGivenName) {
  const Bytes whole = read_file_chars(capture_path(kSample01));
  for (size_t size : {0, 511, 5119, 80000, 156319}) {
    SCOPED_TRACE(size);
    EXPECT_TRUE(throws_file_error([&] { read_c3d_bytes(as_span(whole).first(size), "take.c3d"); }, "take.c3d", "truncated"));
  }
  EXPECT_EQ(read_c3d_bytes(as_span(whole).first(156320), "take.c3d").frame_count, 450);
}

// ---------------------------------------------------------------- the shared captures

struct EncodingSet {
  std::vector<std::string> integer_files, float_files;
  std::vector<std::string> first_labels;
  int points, frames;
  size_t missing;
  double scale;                   // |POINT:SCALE|, the integer step in millimetres
  std::vector<size_t> steps_off;  // per integer file: samples a whole step from the floats
};

// Samples of `a` and `b` (same mask) whose coordinates differ by more than `limit`.
size_t samples_further_than(const Capture& a, const Capture& b, double limit) {
  size_t count = 0;
  for (size_t i = 0; i < a.positions.size(); ++i)
    if (is_present(a.positions[i]) && (a.positions[i] - b.positions[i]).cwiseAbs().maxCoeff() > limit)
      ++count;
  return count;
}

void expect_encodings_agree(const EncodingSet& set) {
  const Capture reference = read_c3d(capture_path(set.float_files[0]));
  ASSERT_EQ(reference.point_count(), set.points);
  EXPECT_EQ(reference.frame_count, set.frames);
  EXPECT_DOUBLE_EQ(reference.rate_hz, 50.0);
  EXPECT_EQ(reference.first_frame, 1);
  EXPECT_EQ(missing_count(reference), set.missing);
  EXPECT_EQ(
      std::vector<std::string>(reference.labels.begin(), reference.labels.begin() + set.first_labels.size()),
      set.first_labels);
  for (const std::string& file : set.float_files) {
    SCOPED_TRACE(file);
    expect_same_capture(reference, read_c3d(capture_path(file)),
                        0.0);  // IEEE and VAX floats decode identically
  }
  for (size_t i = 0; i < set.integer_files.size(); ++i) {
    SCOPED_TRACE(set.integer_files[i]);
    const Capture c = read_c3d(capture_path(set.integer_files[i]));
    // Same labels, frames and missing mask; coordinates within one integer step of the floats...
    expect_same_capture(reference, c, set.scale + 1e-3);
    // ...and within half a step except where that file's converter rounded the other way.
    EXPECT_EQ(samples_further_than(reference, c, set.scale / 2 + 1e-3), set.steps_off[i]);
  }
}

TEST(C3dSharedCaptures, Sample01SixEncodingsAgree) {
  expect_encodings_agree(
      {{"c3d-org/sample01/Eb015pi.c3d", "c3d-org/sample01/Eb015si.c3d", "c3d-org/sample01/Eb015vi.c3d"},
       {"c3d-org/sample01/Eb015pr.c3d", "c3d-org/sample01/Eb015sr.c3d", "c3d-org/sample01/Eb015vr.c3d"},
       {"RFT1", "RFT2", "RFT3", "LFT1"},
       26,
       450,
       226,
       0.0833333358,
       {0, 0, 0}});
  // The three integer files hold the same integers.
  expect_same_capture(read_c3d(capture_path("c3d-org/sample01/Eb015pi.c3d")),
                      read_c3d(capture_path("c3d-org/sample01/Eb015vi.c3d")), 0.0);
  const Capture c = read_c3d(capture_path("c3d-org/sample01/Eb015vr.c3d"));
  EXPECT_EQ(c.labels.back(), "pv4");
  expect_point(c, 0, 0, {248.583344, 226.833344, 37.416668});
  expect_point(c, 449, 0, {324.583344, 2248.000000, 33.750000});
  EXPECT_FALSE(c.present(449, 25));
}

TEST(C3dSharedCaptures, Sample02SixEncodingsAgree) {
  expect_encodings_agree(
      {{"c3d-org/sample02/pc_int.c3d", "c3d-org/sample02/dec_int.c3d", "c3d-org/sample02/sgi_int.c3d"},
       {"c3d-org/sample02/pc_real.c3d", "c3d-org/sample02/dec_real.c3d", "c3d-org/sample02/sgi_real.c3d"},
       {"RFT1", "RFT2", "RFT3", "RSK1"},
       36,
       89,
       228,  // 7.1% of 36 x 89
       0.281181872,
       // pc_int and sgi_int hold the same integers; in 58 samples one coordinate
       // is one step below dec_int and the float files (truncated, not rounded).
       {58, 0, 58}});
  expect_same_capture(read_c3d(capture_path("c3d-org/sample02/pc_int.c3d")),
                      read_c3d(capture_path("c3d-org/sample02/sgi_int.c3d")), 0.0);
  const Capture c = read_c3d(capture_path("c3d-org/sample02/sgi_real.c3d"));
  EXPECT_EQ(c.labels.back(), "LFA3");
  EXPECT_FALSE(c.present(0, 0));
  expect_point(c, 88, 35, {-26.431095, 2280.385010, 984.136536});
}

TEST(C3dSharedCaptures, Cmu85_02) {
  const Capture c = read_c3d(capture_path("cmu/85_02.c3d"));
  EXPECT_EQ(c.point_count(), 41);
  EXPECT_EQ(c.frame_count, 810);
  EXPECT_DOUBLE_EQ(c.rate_hz, 120.0);
  EXPECT_EQ(c.first_frame, 1);
  const CaptureSummary s = summarize(c);
  EXPECT_EQ(s.labelled, 41);
  EXPECT_EQ(s.unlabelled, 0);
  EXPECT_EQ(missing_count(c), 0u);
  EXPECT_EQ(c.labels.front(), "Male:LFWT");
  expect_point(c, 0, 0, {116.397980, 1075.617432, 991.907959});
  expect_point(c, 809, 40, {-527.538086, -510.073608, 907.442505});
}

TEST(C3dSharedCaptures, Cmu85_12) {
  const Capture c = read_c3d(capture_path("cmu/85_12.c3d"));
  EXPECT_EQ(c.point_count(), 41);
  EXPECT_EQ(c.frame_count, 4499);
  EXPECT_DOUBLE_EQ(c.rate_hz, 120.0);
  EXPECT_EQ(missing_count(c), 0u);
}

TEST(C3dSharedCaptures, Hdm05KeepsUnlabelledPoints) {
  const Capture c = read_c3d(capture_path("hdm05/HDM_bd_05-01_01_120.c3d"));
  EXPECT_EQ(c.point_count(), 44);
  EXPECT_EQ(c.frame_count, 5920);
  EXPECT_DOUBLE_EQ(c.rate_hz, 120.0);
  const CaptureSummary s = summarize(c);
  EXPECT_EQ(s.labelled, 41);
  EXPECT_EQ(s.unlabelled, 3);
  EXPECT_EQ(c.unlabelled_points(), (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(c.labels[0], "*0");
  EXPECT_EQ(c.labels[3], "Bastian:LFHD");
  EXPECT_EQ(missing_count(c), 0u);  // the unlabelled channels too
}

TEST(C3dSharedCaptures, Hdm05FirstFrame) {
  const Capture c = read_c3d(capture_path("hdm05/HDM_dg_06-03_03_120.c3d"));
  EXPECT_EQ(c.first_frame, 2925);
  EXPECT_EQ(c.frame_count, 202);
  EXPECT_EQ(c.point_count(), 44);
}

TEST(C3dSharedCaptures, BasketSprintHasRealGapsAndIsInMetres) {
  const Capture c = read_c3d(capture_path("kineticstoolkit/kinematics_basket_sprint.c3d"));
  EXPECT_EQ(c.point_count(), 26);
  EXPECT_EQ(c.frame_count, 3678);
  EXPECT_DOUBLE_EQ(c.rate_hz, 120.0);
  EXPECT_EQ(c.first_frame, 0);
  const CaptureSummary s = summarize(c);
  EXPECT_EQ(s.labelled, 26);
  // Measured: 37068 of 26 x 3678 samples (negative residuals), 0.3876; PROVENANCE says ~39%.
  EXPECT_EQ(missing_count(c), 37068u);
  EXPECT_GT(s.missing_fraction, 0.35);
  EXPECT_LT(s.missing_fraction, 0.43);
  EXPECT_FALSE(s.gaps.empty());
  // POINT:UNITS is "m": stored -3.5246613 m is -3524.66 mm.
  expect_point(c, 0, 0, {-3524.661377, 215.199661, 110.191338});
}

TEST(C3dSharedCaptures, TennisServeNanGapsAreMissing) {
  const Capture complete = read_c3d(capture_path("kineticstoolkit/kinematics_tennis_serve.c3d"));
  const Capture gapped = read_c3d(capture_path("kineticstoolkit/kinematics_tennis_serve_nan.c3d"));
  EXPECT_EQ(complete.point_count(), 39);
  EXPECT_EQ(complete.frame_count, 1092);
  EXPECT_DOUBLE_EQ(complete.rate_hz, 50.0);
  EXPECT_EQ(missing_count(complete), 0u);
  // The injected gap is stored as NaN coordinates (residuals are not negative): 145 samples of point 30.
  EXPECT_EQ(missing_count(gapped), 145u);
  ASSERT_EQ(gapped.positions.size(), complete.positions.size());
  for (int f = 0; f < gapped.frame_count; ++f)
    for (int p = 0; p < gapped.point_count(); ++p) {
      if (gapped.present(f, p))
        ASSERT_EQ(gapped.at(f, p), complete.at(f, p));
      else
        ASSERT_EQ(p, 30);
    }
}

TEST(C3dSharedCaptures, SampleJumpSkipsAnalogSamples) {
  // 16 analog channels at 600 Hz with points at 120 Hz: 80 analog words after each frame's points.
  const Capture c = read_c3d(capture_path("c3d-org/Sample_Jump2.c3d"));
  EXPECT_EQ(c.point_count(), 51);
  EXPECT_EQ(c.frame_count, 264);
  EXPECT_DOUBLE_EQ(c.rate_hz, 120.0);
  EXPECT_EQ(missing_count(c), 0u);
  expect_point(c, 263, 0, {475.928711, 249.153625, 1725.336548});
  expect_point(c, 263, 50, {676.407410, 65.755127, 63.939186});
}

// ---------------------------------------------------------------- writing

struct Storage {
  C3dProcessor processor;
  bool float_storage;
  const char* name;
};

const Storage kAllStorages[] = {
    {C3dProcessor::Intel, true, "intel_float"}, {C3dProcessor::Intel, false, "intel_int"},
    {C3dProcessor::Dec, true, "dec_float"},     {C3dProcessor::Dec, false, "dec_int"},
    {C3dProcessor::Mips, true, "mips_float"},   {C3dProcessor::Mips, false, "mips_int"},
};

// Float storage is exact for coordinates read from C3D (they are floats); integer storage is
// within half the chosen scale, which maps the largest coordinate to 32000.
double round_trip_tolerance(const Capture& c, bool float_storage) {
  if (float_storage) return 0.0;
  const double largest = max_abs_coordinate(c);
  return largest / 32000 / 2 + largest * 1e-6;
}

void expect_c3d_round_trips(const Capture& original, const std::string& stem) {
  for (const Storage& storage : kAllStorages) {
    SCOPED_TRACE(storage.name);
    const std::string path = scratch_path(stem + "_" + storage.name + ".c3d");
    write_c3d(original, path, {storage.processor, storage.float_storage});
    expect_same_capture(original, read_c3d(path), round_trip_tolerance(original, storage.float_storage));
  }
}

TEST(C3dWrite, RoundTripsAllProcessorsAndStoragesWithGaps) {
  expect_c3d_round_trips(read_c3d(capture_path(kSample01)), "c3d_rt_sample01");
  expect_c3d_round_trips(read_c3d(capture_path("kineticstoolkit/kinematics_basket_sprint.c3d")),
                         "c3d_rt_basket");
  expect_c3d_round_trips(read_c3d(capture_path("hdm05/HDM_dg_06-03_03_120.c3d")), "c3d_rt_hdm05");
}

TEST(C3dWrite, WritesTheDeclaredProcessorAndStorage) {
  const Capture c = read_c3d(capture_path("cmu/85_02.c3d"));
  const std::string path = scratch_path("c3d_layout.c3d");
  for (const Storage& storage : kAllStorages) {
    SCOPED_TRACE(storage.name);
    write_c3d(c, path, {storage.processor, storage.float_storage});
    const Bytes b = read_file_chars(path);
    ASSERT_GE(b.size(), 1024u);
    EXPECT_EQ(b[0], 2);
    EXPECT_EQ(static_cast<uint8_t>(b[1]), 0x50);
    EXPECT_EQ(static_cast<uint8_t>(b[512 + 3]), 84 + static_cast<int>(storage.processor));
    EXPECT_EQ(b.size() % 512, 0u);
    const size_t parameter_blocks = static_cast<uint8_t>(b[512 + 2]);
    const size_t frame_bytes = 41 * (storage.float_storage ? 16 : 8);
    EXPECT_GE(b.size(), (1 + parameter_blocks) * 512 + 810 * frame_bytes);
  }
  // The Intel file's parameters, read back with the test's own minimal walker.
  write_c3d(c, path, {C3dProcessor::Intel, false});
  const Bytes b = read_file_chars(path);
  EXPECT_EQ(get_u16(b, locate(b, "POINT", "USED").data), 41);
  EXPECT_EQ(get_u16(b, locate(b, "POINT", "FRAMES").data), 810);
  EXPECT_EQ(get_u16(b, locate(b, "ANALOG", "USED").data), 0);
  float scale;
  std::memcpy(&scale, &b[locate(b, "POINT", "SCALE").data], 4);
  EXPECT_GT(scale, 0.0f);  // integer storage
  EXPECT_EQ(std::string(&b[locate(b, "POINT", "UNITS").data], 2), "mm");
  EXPECT_EQ(std::string(&b[locate(b, "POINT", "LABELS").data], 9), "Male:LFWT");
  locate(b, "POINT", "DESCRIPTIONS");
  locate(b, "TRIAL", "ACTUAL_END_FIELD");
}

Capture synthetic_capture(int points, int frames, unsigned seed) {
  std::vector<std::string> labels;
  for (int p = 0; p < points; ++p)
    labels.push_back(p % 50 == 7 ? "*" + std::to_string(p) : "Marker_" + std::to_string(p));
  labels[1] = "";  // unlabelled, unnamed
  Capture c(labels, frames, 100.0);
  std::mt19937 random(seed);
  std::uniform_real_distribution<float> coordinate(-2500.0f, 2500.0f);
  for (Vec3& p : c.positions) p = Vec3(coordinate(random), coordinate(random), coordinate(random));
  for (int f = 0; f < frames; ++f) c.at(f, 0) = missing_point();      // a channel never seen
  for (int f = 0; f < frames / 2; ++f) c.at(f, 2) = missing_point();  // a gap at the start
  c.at(frames - 1, points - 1) = missing_point();                     // and one at the end
  return c;
}

TEST(C3dWrite, MoreThan255LabelsUseLabels2) {
  const Capture original = synthetic_capture(300, 6, 1);
  expect_c3d_round_trips(original, "c3d_rt_300");
  const Bytes b = read_file_chars(scratch_path("c3d_rt_300_intel_float.c3d"));
  EXPECT_EQ(b[locate(b, "POINT", "LABELS").type + 3], static_cast<char>(255));
  EXPECT_EQ(b[locate(b, "POINT", "LABELS2").type + 3], 45);
  const Capture back = read_c3d(scratch_path("c3d_rt_300_mips_int.c3d"));
  EXPECT_EQ(back.labels[1], "");
  EXPECT_FALSE(back.is_labelled(1));
  EXPECT_EQ(back.labels[257], "*257");
  EXPECT_EQ(back.labels[299], "Marker_299");
}

TEST(C3dWrite, FrameCountsBeyondSixteenBits) {
  // 40000 frames: POINT:FRAMES holds the 16 bits that a signed reader would see as -25536.
  const Capture unsigned_count = synthetic_capture(2, 40000, 4);
  const std::string path = scratch_path("c3d_40000.c3d");
  write_c3d(unsigned_count, path);
  Bytes b = read_file_chars(path);
  EXPECT_EQ(get_u16(b, locate(b, "POINT", "FRAMES").data), 40000);
  EXPECT_EQ(read_c3d(path).frame_count, 40000);

  // Beyond 65535 only the TRIAL fields (two 16-bit words each) hold the range.
  Capture original = synthetic_capture(2, 70000, 2);
  original.first_frame = 5;
  expect_c3d_round_trips(original, "c3d_rt_long");
  // Writers that keep the low 16 bits in POINT:FRAMES (70000 - 65536) are understood too.
  b = read_file_chars(scratch_path("c3d_rt_long_intel_int.c3d"));
  put_u16(b, locate(b, "POINT", "FRAMES").data, 70000 - 65536);
  write_file_chars(path, b);
  EXPECT_EQ(read_c3d(path).frame_count, 70000);

  Capture late = synthetic_capture(3, 4, 3);
  late.first_frame = 100000;  // beyond the header's 16-bit first frame
  expect_c3d_round_trips(late, "c3d_rt_late");
}

TEST(C3dWrite, DecFloatsKeepExtremeValues) {
  // Float literals: only float values can survive float storage exactly.
  Capture c({"a", "b", "c"}, 2, 240.0);
  c.at(0, 0) = Vec3(1e-30f, -3e30f, 1.17549435e-38f);            // tiny, huge, the smallest normal IEEE float
  c.at(0, 1) = Vec3(std::ldexp(1.0f, -127), -12345.678f, 0.5f);  // an IEEE denormal VAX holds normally
  c.at(0, 2) = Vec3(1.0f / 3.0f, -1.0f, 1e20f);
  c.at(1, 0) = Vec3(0.0, 0.0, 1.0);
  c.at(1, 1) = Vec3(-0.0, 2.0, -1.0);
  c.at(1, 2) = missing_point();
  for (C3dProcessor processor : {C3dProcessor::Dec, C3dProcessor::Mips, C3dProcessor::Intel}) {
    const std::string path = scratch_path("c3d_extremes.c3d");
    write_c3d(c, path, {processor, true});
    expect_same_capture(c, read_c3d(path), 0.0);
  }
}

TEST(C3dWrite, DecimalRatesSurviveFloatStorage) {
  // POINT:RATE is a float; 59.94 must not come back as 59.94000244140625.
  const auto round_trip = [](double rate) {
    Capture c({"a"}, 2, rate);
    c.at(0, 0) = Vec3(1, 2, 3);
    const std::string path = scratch_path("c3d_rate_decimal.c3d");
    write_c3d(c, path, {C3dProcessor::Dec, true});
    return read_c3d(path).rate_hz;
  };
  for (double rate : {59.94, 119.88, 29.97, 240.0}) EXPECT_EQ(round_trip(rate), rate);
  EXPECT_NEAR(round_trip(1000.0 / 3.0), 1000.0 / 3.0, 1e-4);  // beyond float precision
}

TEST(C3dWrite, IntegerStorageKeepsSamplesNearTheOrigin) {
  Capture c({"far", "near"}, 1, 100.0);
  c.at(0, 0) = Vec3(3000.0, 0.0, 0.0);
  c.at(0, 1) = Vec3(0.001, 0.0, -0.002);  // rounds to (0,0,0), which would read as missing
  const std::string path = scratch_path("c3d_near_origin.c3d");
  write_c3d(c, path, {C3dProcessor::Intel, false});
  const Capture back = read_c3d(path);
  EXPECT_TRUE(back.present(0, 1));
  EXPECT_LE((back.at(0, 1) - c.at(0, 1)).norm(), 3000.0 / 32000 * 1.5);
}

TEST(C3dWrite, RefusesCapturesItCannotStore) {
  const std::string path = scratch_path("c3d_refused.c3d");
  Capture no_rate({"a"}, 2, 0.0);
  EXPECT_TRUE(throws_file_error([&] { write_c3d(no_rate, path); }, path, "frame rate"));
  Capture wrong_size({"a", "b"}, 2, 100.0);
  wrong_size.positions.pop_back();
  EXPECT_TRUE(throws_file_error([&] { write_c3d(wrong_size, path); }, path, "positions"));
  Capture negative_first({"a"}, 2, 100.0);
  negative_first.first_frame = -3;
  EXPECT_TRUE(throws_file_error([&] { write_c3d(negative_first, path); }, path, "negative first frame"));
  const std::string no_folder = scratch_path("no_such_folder/x.c3d");
  EXPECT_TRUE(
      throws_file_error([&] { write_c3d(Capture({"a"}, 1, 100.0), no_folder); }, no_folder, "cannot open"));
}

}  // namespace
}  // namespace skinstream
