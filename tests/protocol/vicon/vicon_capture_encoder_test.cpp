// Several recordings as several subjects of one Vicon DataStream: one frame of each in every
// packet, subject ids in order, trajectory ids kept apart, a subject listed only while its
// recording has a marker, each recording looping on its own, and recordings that cannot share a
// stream refused. (One recording's packets are checked against fixtures in vicon_datastream_test.)
#include "protocol/vicon/vicon_capture_encoder.h"

#include <gtest/gtest.h>

#include "protocol/vicon/vicon_packet_reader.h"

namespace skinstream::vicon {
namespace {

// Markers "A" and "B" (x = base + frame) and an unlabelled "*5"; `blank` frames have no marker.
Capture actor(int frames, double base, std::vector<int> blank = {}) {
  Capture c({"A", "B", "*5"}, frames, 120.0);
  c.first_frame = 1;
  for (int f = 0; f < frames; ++f)
    for (int p = 0; p < 3; ++p) c.at(f, p) = Vec3(base + f, 10.0 * p, 1000.0);
  for (int f : blank)
    for (int p = 0; p < 2; ++p) c.at(f, p) = missing_point();
  return c;
}

DecodedPacket encode(CaptureFrameEncoder& encoder, uint64_t sequence, bool include_static) {
  PacketWriter writer;
  encoder.encode_frame(sequence, static_cast<uint32_t>(sequence + 1), include_static, writer);
  const auto packet = writer.finish();
  DecodedPacket out;
  std::string error;
  EXPECT_TRUE(decode_packet(std::vector<unsigned char>(packet.begin(), packet.end()), out, error)) << error;
  return out;
}

TEST(CaptureFrameEncoder, SeveralRecordingsAreSeveralSubjectsOfOneFrame) {
  const Capture one = actor(4, 0.0), two = actor(4, 5000.0);
  CaptureFrameEncoder encoder(std::vector<ReplaySubject>{{"Actor1", &one}, {"Actor2", &two}});
  const DecodedPacket d = encode(encoder, 2, true);
  ASSERT_EQ(d.subjects.size(), 2u);
  EXPECT_EQ(d.subjects[0].name, "Actor1");
  EXPECT_EQ(d.subjects[0].subject_id, 1u);
  EXPECT_EQ(d.subjects[1].name, "Actor2");
  EXPECT_EQ(d.subjects[1].subject_id, 2u);
  ASSERT_EQ(d.subjects[1].markers.size(), 2u);
  EXPECT_EQ(d.subjects[1].markers[1].name, "B");  // the same names under each subject
  ASSERT_EQ(d.labeled.size(), 4u);
  for (const LabeledRecon& r : d.labeled) {
    const double base = r.subject_id == 1 ? 0.0 : 5000.0;  // frame 2 of each recording
    EXPECT_EQ(r.position[0], base + 2) << r.subject_id;
    EXPECT_EQ(r.position[1], 10.0 * r.marker_id) << r.subject_id;
  }
  ASSERT_EQ(d.unlabeled.size(), 2u);
  EXPECT_EQ(d.unlabeled[0].trajectory_id, 5u);
  EXPECT_EQ(d.unlabeled[1].trajectory_id, (1u << 24) + 5u);  // the second recording's ids kept apart
  EXPECT_EQ(d.frame_info.frame_id, 2u);
}

TEST(CaptureFrameEncoder, ASubjectWithoutMarkersLeavesTheListAndComesBack) {
  const Capture one = actor(6, 0.0), two = actor(6, 5000.0, {2, 3});
  CaptureFrameEncoder encoder(std::vector<ReplaySubject>{{"Actor1", &one}, {"Actor2", &two}});
  EXPECT_EQ(encoder.listed(1), 3u);
  EXPECT_EQ(encoder.listed(2), 1u);
  EXPECT_EQ(encoder.listed(4), 3u);
  const DecodedPacket off = encode(encoder, 2, true);
  ASSERT_EQ(off.subjects.size(), 1u);
  EXPECT_EQ(off.subjects[0].name, "Actor1");
  for (const LabeledRecon& r : off.labeled) EXPECT_EQ(r.subject_id, 1u);
  EXPECT_EQ(off.unlabeled.size(), 2u);  // its unlabelled points are still in the volume
  EXPECT_EQ(encode(encoder, 4, true).subjects.size(), 2u);
}

TEST(CaptureFrameEncoder, ShorterRecordingsEndOrLoopOnTheirOwn) {
  const Capture longer = actor(5, 0.0), shorter = actor(2, 5000.0);
  CaptureFrameEncoder once(std::vector<ReplaySubject>{{"Long", &longer}, {"Short", &shorter}});
  EXPECT_EQ(once.frame_count(), 5);
  EXPECT_EQ(once.listed(1), 3u);
  EXPECT_EQ(once.listed(2), 1u);  // Short has ended
  CaptureFrameEncoder looped(std::vector<ReplaySubject>{{"Long", &longer}, {"Short", &shorter}}, 0.0, true);
  EXPECT_EQ(looped.listed(3), 3u);
  const DecodedPacket d = encode(looped, 3, false);
  for (const LabeledRecon& r : d.labeled)
    if (r.subject_id == 2) {
      EXPECT_EQ(r.position[0], 5000.0 + 1);  // its frame 3 mod 2
    }
}

TEST(CaptureFrameEncoder, RecordingsThatCannotShareAStreamAreRefused) {
  Capture at_100 = actor(2, 0.0);
  at_100.rate_hz = 100.0;
  const Capture at_120 = actor(2, 0.0);
  try {
    CaptureFrameEncoder encoder(std::vector<ReplaySubject>{{"A", &at_120}, {"B", &at_100}});
    FAIL() << "two rates in one stream";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("different rates"), std::string::npos) << e.what();
  }
  EXPECT_THROW(CaptureFrameEncoder(std::vector<ReplaySubject>{}), std::invalid_argument);
}

}  // namespace
}  // namespace skinstream::vicon
