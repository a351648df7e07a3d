// Recordings as QTM streams them (protocol/qtm_capture_encoder): prefixed labels in order, a
// position per label with NaN for missing, unlabelled points with unique ids, several subjects.
#include <gtest/gtest.h>

#include <cmath>

#include "protocol/qtm/qtm_capture_encoder.h"
#include "protocol/qtm/qtm_packet_reader.h"
#include "support/allocation_counter.h"

namespace skinstream::qtm {
namespace {

Capture tiny_capture() {  // channels A, B, *7; frame index 1 has B missing
  Capture c({"A", "B", "*7"}, 2, 120.0);
  c.first_frame = 10;
  c.at(0, 0) = Vec3(1, 2, 3);
  c.at(0, 1) = Vec3(4, 5, 6);
  c.at(0, 2) = Vec3(7, 8, 9);
  c.at(1, 0) = Vec3(10, 20, 30);
  c.at(1, 1) = missing_point();
  c.at(1, 2) = Vec3(-1, -2, -3);
  return c;
}

DataFrame decoded(std::span<const unsigned char> packet) {
  DataFrame frame;
  std::string error;
  EXPECT_TRUE(decode_data(packet, frame, error)) << error;
  return frame;
}

TEST(QtmCaptureEncoder, OneSubject) {
  const Capture capture = tiny_capture();
  CaptureEncoder encoder({{"tiny_take", &capture}});
  EXPECT_EQ(encoder.parameters().labels, (std::vector<std::string>{"tiny-take_A", "tiny-take_B"}));
  EXPECT_DOUBLE_EQ(encoder.parameters().frequency_hz, 120.0);
  DataPacketWriter writer;
  const DataFrame f = decoded(encoder.encode_frame(1, writer));
  EXPECT_EQ(f.frame_number, 11u);
  EXPECT_EQ(f.timestamp_us, 8333);  // 1 / 120 s
  ASSERT_EQ(f.labelled.size(), 2u);
  EXPECT_EQ(f.labelled[0], (std::array<float, 3>{10, 20, 30}));
  EXPECT_TRUE(std::isnan(f.labelled[1][0]));
  ASSERT_EQ(f.unlabelled.size(), 1u);
  EXPECT_EQ(f.unlabelled[0].id, 7u);
  EXPECT_EQ(f.unlabelled[0].position, (std::array<float, 3>{-1, -2, -3}));
  // Index 2 loops back to frame 0 of the take with a rising frame number.
  const DataFrame looped = decoded(encoder.encode_frame(2, writer));
  EXPECT_EQ(looped.frame_number, 12u);
  EXPECT_EQ(looped.labelled[1], (std::array<float, 3>{4, 5, 6}));
}

TEST(QtmCaptureEncoder, SeveralSubjectsLastAsLongAsTheLongest) {
  const Capture a = tiny_capture();
  Capture b({"X"}, 3, 120.0);
  for (int i = 0; i < 3; ++i) b.at(i, 0) = Vec3(i, i, i);
  Capture c = tiny_capture();
  CaptureEncoder encoder({{"A1", &a}, {"A2", &b}, {"A3", &c}});
  EXPECT_EQ(encoder.frame_count(), 3);
  EXPECT_EQ(encoder.parameters().labels,
            (std::vector<std::string>{"A1_A", "A1_B", "A2_X", "A3_A", "A3_B"}));
  DataPacketWriter writer;
  const DataFrame f = decoded(encoder.encode_frame(2, writer));
  ASSERT_EQ(f.labelled.size(), 5u);
  EXPECT_TRUE(std::isnan(f.labelled[0][0]));  // A1 has ended
  EXPECT_EQ(f.labelled[2], (std::array<float, 3>{2, 2, 2}));
  const DataFrame first = decoded(encoder.encode_frame(0, writer));
  ASSERT_EQ(first.unlabelled.size(), 2u);  // A1's and A3's *7, kept apart
  EXPECT_EQ(first.unlabelled[0].id, 7u);
  EXPECT_EQ(first.unlabelled[1].id, 7u + 2 * CaptureEncoder::kUnlabelledIdStride);
}

TEST(QtmCaptureEncoder, EncodingAFrameAllocatesNothingOnceWarm) {
  const Capture capture = tiny_capture();
  CaptureEncoder encoder({{"t", &capture}});
  DataPacketWriter writer;
  encoder.encode_frame(0, writer);
  test::CountAllocations counted;
  for (uint64_t k = 1; k < 50; ++k) encoder.encode_frame(k, writer);
  EXPECT_EQ(counted.count(), 0u);
}

}  // namespace
}  // namespace skinstream::qtm
