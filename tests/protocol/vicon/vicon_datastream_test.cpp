// The Vicon DataStream wire format against golden fixtures written independently of the encoder
// (tests/protocol/fixtures/vicon/make_fixtures.py packs each object with Python's struct from the
// SDK's field orders), plus hand-written bytes, truncation and random corruption.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <random>

#include "protocol/vicon/vicon_capture_encoder.h"
#include "protocol/vicon/vicon_datastream.h"
#include "protocol/vicon/vicon_packet_framer.h"
#include "protocol/vicon/vicon_packet_reader.h"
#include "protocol/vicon/vicon_packet_writer.h"
#include "support/test_data.h"

namespace skinstream::vicon {
namespace {

using ByteVector = std::vector<unsigned char>;

ByteVector fixture(const std::string& name) {
  const std::string path = test::source_path("tests/protocol/fixtures/vicon/" + name);
  std::ifstream in(path, std::ios::binary);
  EXPECT_TRUE(in.good()) << "missing fixture " << path;
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

ByteVector bytes_of(std::span<const unsigned char> s) { return {s.begin(), s.end()}; }

DecodedPacket decoded(const ByteVector& packet) {
  DecodedPacket out;
  std::string error;
  EXPECT_TRUE(decode_packet(packet, out, error)) << error;
  return out;
}

SubjectInfo walker_subject() {
  SubjectInfo s;
  s.subject_id = 1;
  s.name = "walker";
  s.segments.push_back({0, 1, {-1.f, -2.f, -3.f, 1.f, 2.f, 3.f}, "pelvis"});
  s.markers = {{0, "LASI"}, {1, "RASI"}};
  s.attachments = {{0, 1}, {1, 1}};
  return s;
}

std::vector<LabeledRecon> two_labelled() {
  LabeledRecon a;
  a.subject_id = 1;
  a.marker_id = 0;
  a.radius = 7.0;
  a.position = {100.5, -200.25, 950.125};
  a.trajectory_id = 3;
  LabeledRecon b = a;
  b.marker_id = 1;
  b.position = {1e-3, 0.0, -1.5};
  for (int i = 0; i < 9; ++i) b.covariance[i] = i;
  b.trajectory_id = 4;
  return {a, b};
}

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

// ---- Hand-written bytes: the field orders, spelled out ----

TEST(ViconWire, RequestFramePushIsSpelledOutByHand) {
  const ByteVector expected = {
      0x01, 0x00, 0x2B, 0x1A,  // u32 packet magic 0x1A2B0001
      0x09, 0x00, 0x00, 0x00,  // u32 packet length: one 8-byte object header + 1 byte
      0xA2, 0x86, 0x01, 0x00,  // u32 object type RequestFrame = 100002
      0x01, 0x00, 0x00, 0x00,  // u32 object length 1
      0x01,                    // bool m_bStreaming = true (ServerPush)
  };
  EXPECT_EQ(encode_packet(RequestFrame{true}), expected);
  EXPECT_EQ(fixture("request_frame_push.bin"), expected);
}

TEST(ViconWire, TimecodeWritesStandardBeforeUserBitsByHand) {
  Timecode tc;
  tc.hours = 1, tc.minutes = 2, tc.seconds = 3, tc.frames = 4;
  tc.subframes = 2, tc.subframes_per_frame = 5, tc.standard = kTimecodeFilm, tc.user_bits = 0xDEADBEEF;
  tc.field_flag = 1;
  const ByteVector expected = {
      0x01, 0x00, 0x2B, 0x1A, 0x19, 0x00, 0x00, 0x00,  // packet magic, length 25
      0x17, 0x00, 0x00, 0x00, 0x11, 0x00, 0x00, 0x00,  // type Timecode = 23, length 17
      0x01, 0x02, 0x03, 0x04,                          // u8 hours, minutes, seconds, frames
      0x02, 0x00, 0x05, 0x00,                          // u16 subframes, u16 subframes per frame
      0x03, 0x00, 0x00, 0x00,                          // u32 standard (Film), before ...
      0xEF, 0xBE, 0xAD, 0xDE,                          // ... u32 user bits
      0x01,                                            // u8 field flag
  };
  EXPECT_EQ(encode_packet(tc), expected);
  EXPECT_EQ(fixture("timecode.bin"), expected);
}

TEST(ViconWire, StreamInfoAt120HzIsPeriodInTicksByHand) {
  const ByteVector expected = {
      0x01, 0x00, 0x2B, 0x1A, 0x10, 0x00, 0x00, 0x00,  // packet magic, length 16
      0x01, 0x00, 0x00, 0x00, 0x08, 0x00, 0x00, 0x00,  // type StreamInfo = 1, length 8
      0x88, 0x2A, 0x11, 0x00, 0x00, 0x00, 0x00, 0x00,  // i64 frame period 1'125'000 = 0x112A88 ticks of 135 MHz
  };
  EXPECT_EQ(frame_period_ticks(120.0), 1'125'000);
  EXPECT_EQ(encode_packet(StreamInfo{frame_period_ticks(120.0)}), expected);
  EXPECT_EQ(fixture("stream_info_120hz.bin"), expected);
  EXPECT_DOUBLE_EQ(rate_from_period(1'125'000), 120.0);
}

// ---- Encoding equals the fixtures; decoding the fixtures gives the values ----

TEST(ViconWire, ObjectEnumsMatchesFixture) {
  const ByteVector bytes = fixture("object_enums.bin");
  EXPECT_EQ(encode_packet(CaptureFrameEncoder::offered_types()), bytes);
  EXPECT_EQ(decoded(bytes).object_enums.types, CaptureFrameEncoder::offered_types().types);
}

TEST(ViconWire, RequestFramePullMatchesFixture) {
  const ByteVector bytes = fixture("request_frame_pull.bin");
  EXPECT_EQ(encode_packet(RequestFrame{false}), bytes);
  const DecodedPacket d = decoded(bytes);
  ASSERT_TRUE(d.has(object_type::RequestFrame));
  EXPECT_FALSE(d.request_frame.streaming);
  EXPECT_TRUE(decoded(fixture("request_frame_push.bin")).request_frame.streaming);
}

TEST(ViconWire, SubjectInfoMatchesFixture) {
  const ByteVector bytes = fixture("subject_info.bin");
  EXPECT_EQ(encode_packet(walker_subject()), bytes);
  const DecodedPacket d = decoded(bytes);
  ASSERT_EQ(d.subjects.size(), 1u);
  const SubjectInfo& s = d.subjects[0];
  EXPECT_EQ(s.subject_id, 1u);
  EXPECT_EQ(s.name, "walker");
  ASSERT_EQ(s.segments.size(), 1u);
  EXPECT_EQ(s.segments[0].name, "pelvis");
  EXPECT_EQ(s.segments[0].segment_id, 1u);
  EXPECT_FLOAT_EQ(s.segments[0].bounds[2], -3.f);
  ASSERT_EQ(s.markers.size(), 2u);
  EXPECT_EQ(s.markers[1].name, "RASI");
  EXPECT_EQ(s.markers[1].marker_id, 1u);
  ASSERT_EQ(s.attachments.size(), 2u);
  EXPECT_EQ(s.attachments[1].segment_id, 1u);
}

TEST(ViconWire, FrameInfoMatchesFixture) {
  const ByteVector bytes = fixture("frame_info.bin");
  EXPECT_EQ(encode_packet(FrameInfo{41}), bytes);
  EXPECT_EQ(decoded(bytes).frame_info.frame_id, 41u);
}

TEST(ViconWire, LabeledReconsMatchFixture) {
  const ByteVector bytes = fixture("labeled_recons.bin");
  const auto recons = two_labelled();
  EXPECT_EQ(encode_packet(recons), bytes);
  EXPECT_EQ(bytes.size(), 8 + 8 + 4 + 2 * kLabeledReconBytes);
  const DecodedPacket d = decoded(bytes);
  ASSERT_EQ(d.labeled.size(), 2u);
  EXPECT_EQ(d.labeled[0].position, recons[0].position);  // float64 on the wire: exact
  EXPECT_EQ(d.labeled[1].covariance, recons[1].covariance);
  EXPECT_EQ(d.labeled[1].marker_id, 1u);
  EXPECT_EQ(d.labeled[1].trajectory_id, 4u);
}

TEST(ViconWire, UnlabeledReconsMatchFixture) {
  const ByteVector bytes = fixture("unlabeled_recons.bin");
  UnlabeledRecon r;
  r.radius = 7.0;
  r.position = {1.0, 2.0, 3.0};
  r.trajectory_id = 7;
  EXPECT_EQ(encode_packet(std::vector<UnlabeledRecon>{r}), bytes);
  const DecodedPacket d = decoded(bytes);
  ASSERT_EQ(d.unlabeled.size(), 1u);
  EXPECT_EQ(d.unlabeled[0].position, r.position);
  EXPECT_EQ(d.unlabeled[0].trajectory_id, 7u);
}

TEST(ViconWire, TimecodeDecodesFromFixture) {
  const Timecode tc = decoded(fixture("timecode.bin")).timecode;
  EXPECT_EQ(tc.hours, 1);
  EXPECT_EQ(tc.frames, 4);
  EXPECT_EQ(tc.subframes_per_frame, 5);
  EXPECT_EQ(tc.standard, kTimecodeFilm);
  EXPECT_EQ(tc.user_bits, 0xDEADBEEFu);
  EXPECT_EQ(tc.field_flag, 1);
}

TEST(ViconWire, CaptureFramePacketMatchesFixture) {
  const Capture capture = tiny_capture();
  CaptureFrameEncoder encoder(capture, "tiny");
  PacketWriter writer;
  encoder.encode_frame(1, static_cast<uint32_t>(capture.first_frame + 1), true, writer);
  const ByteVector bytes = fixture("frame_packet.bin");
  EXPECT_EQ(bytes_of(writer.finish()), bytes);

  const DecodedPacket d = decoded(bytes);
  EXPECT_EQ(d.stream_info.frame_period_ticks, 1'125'000);
  EXPECT_EQ(d.frame_info.frame_id, 10u);  // SDK frame number 11 = first_frame + index
  ASSERT_EQ(d.labeled.size(), 1u);        // B is occluded: left out
  EXPECT_EQ(d.labeled[0].marker_id, 0u);
  EXPECT_EQ(d.labeled[0].position, (std::array<double, 3>{10, 20, 30}));
  ASSERT_EQ(d.unlabeled.size(), 1u);
  EXPECT_EQ(d.unlabeled[0].trajectory_id, 7u);
  EXPECT_EQ(d.timecode.frames, 2);
  EXPECT_EQ(d.timecode.subframes, 1);
  EXPECT_TRUE(d.unknown_types.empty());
}

TEST(ViconWire, FrameWithoutStaticObjectsOmitsThem) {
  const Capture capture = tiny_capture();
  CaptureFrameEncoder encoder(capture, "tiny");
  PacketWriter writer;
  encoder.encode_frame(0, 10, false, writer);
  const DecodedPacket d = decoded(bytes_of(writer.finish()));
  EXPECT_FALSE(d.has(object_type::StreamInfo));
  EXPECT_FALSE(d.has(object_type::SubjectInfo));
  EXPECT_EQ(d.labeled.size(), 2u);
}

TEST(ViconWire, TimecodeFollowsFrameNumber) {
  // 120 Hz: Film 24 fps with 5 subframes. Frame 120*3661 + 7 is 01:01:01, frame 1, subframe 2.
  const Timecode tc = CaptureFrameEncoder::timecode_for(120 * 3661 + 7, 120.0);
  EXPECT_EQ(tc.hours, 1);
  EXPECT_EQ(tc.minutes, 1);
  EXPECT_EQ(tc.seconds, 1);
  EXPECT_EQ(tc.frames, 1);
  EXPECT_EQ(tc.subframes, 2);
  EXPECT_EQ(tc.standard, kTimecodeFilm);
  EXPECT_EQ(CaptureFrameEncoder::timecode_for(100, 100.0).standard, 0u);  // PAL 25 divides 100
}

// ---- Unknown objects are skipped and reported ----

TEST(ViconWire, UnknownObjectsAreSkippedAndReported) {
  PacketWriter writer;
  writer.add(FrameInfo{5});
  const unsigned char junk[] = {1, 2, 3};
  writer.add_raw(9999, junk);
  writer.add(StreamInfo{1'125'000});
  const DecodedPacket d = decoded(bytes_of(writer.finish()));
  EXPECT_EQ(d.unknown_types, std::vector<uint32_t>{9999});
  EXPECT_EQ(d.frame_info.frame_id, 5u);
  EXPECT_EQ(d.stream_info.frame_period_ticks, 1'125'000);
}

// ---- Malformed input: rejected with a reason, never read out of bounds ----

std::string error_of(const ByteVector& packet) {
  DecodedPacket d;
  std::string error;
  return decode_packet(packet, d, error) ? "" : error;
}

TEST(ViconWire, CountsThatExceedThePayloadAreRejected) {
  ByteVector bytes = fixture("labeled_recons.bin");
  bytes[16] = 3;  // the recon count: 3 records of 116 bytes do not fit in 236
  EXPECT_NE(error_of(bytes).find("count 3 exceeds"), std::string::npos) << error_of(bytes);
  ByteVector subject = fixture("subject_info.bin");
  subject[16 + 4] = 0xFF;  // the name length
  EXPECT_NE(error_of(subject).find("overruns"), std::string::npos) << error_of(subject);
}

// ---- Hostile descriptions: periods and counts a real system never sends ----

std::string stream_info_error(int64_t period_ticks) { return error_of(encode_packet(StreamInfo{period_ticks})); }

TEST(ViconLimits, StreamInfoPeriodsOutside1HzTo10kHzAreRejectedNamingTheRate) {
  EXPECT_EQ(stream_info_error(frame_period_ticks(120.0)), "");
  EXPECT_EQ(stream_info_error(kMinFramePeriodTicks), "");  // 10 kHz
  EXPECT_EQ(stream_info_error(kMaxFramePeriodTicks), "");  // 1 Hz
  EXPECT_EQ(stream_info_error(1), "StreamInfo: frame period of 1 ticks (1.35e+08 Hz) is outside 1 Hz to 10 kHz");
  EXPECT_NE(stream_info_error(kMinFramePeriodTicks - 1).find("(10000.7 Hz) is outside"), std::string::npos);
  EXPECT_NE(stream_info_error(kMaxFramePeriodTicks + 1).find("is outside 1 Hz to 10 kHz"), std::string::npos);
  // 1.5e-11 Hz, and periods with no rate at all.
  EXPECT_NE(stream_info_error(9'000'000'000'000'000'000).find("(1.5e-11 Hz)"), std::string::npos);
  EXPECT_EQ(stream_info_error(0), "StreamInfo: frame period of 0 ticks (no rate) is outside 1 Hz to 10 kHz");
  EXPECT_NE(stream_info_error(INT64_MIN).find("(no rate)"), std::string::npos);
}

SubjectInfo subject_with(int markers, size_t name_bytes = 4) {
  SubjectInfo s;
  s.subject_id = 7;
  s.name = "hostile";
  for (int m = 0; m < markers; ++m) {
    std::string name = "M" + std::to_string(m);
    name.resize(std::max(name.size(), name_bytes), 'x');
    s.markers.push_back({static_cast<uint32_t>(m), name});
  }
  return s;
}

std::string subject_error(const SubjectInfo& subject, const DescriptionLimits& limits = {}) {
  DecodedPacket d;
  std::string error;
  return decode_packet(encode_packet(subject), d, error, limits) ? "" : error;
}

TEST(ViconLimits, SubjectInfoBeyondTheMarkerAndNameCapsIsRejectedSayingWhich) {
  const DescriptionLimits defaults;
  EXPECT_EQ(subject_error(subject_with(static_cast<int>(defaults.max_markers_per_subject))), "");
  // The flood a hostile source sent: 10,000 new names in one SubjectInfo.
  EXPECT_EQ(subject_error(subject_with(10'000)), "SubjectInfo: marker count 10000 exceeds the limit of 1024");
  EXPECT_EQ(subject_error(subject_with(1, defaults.max_name_bytes)), "");
  EXPECT_EQ(subject_error(subject_with(1, defaults.max_name_bytes + 1)), "SubjectInfo: marker name of 257 bytes exceeds the limit of 256");

  DescriptionLimits tight;
  tight.max_markers_per_subject = 2;
  tight.max_name_bytes = 7;
  EXPECT_EQ(subject_error(walker_subject(), tight), "");  // 1 segment, 2 markers, names of up to 6 bytes
  EXPECT_EQ(subject_error(subject_with(3), tight), "SubjectInfo: marker count 3 exceeds the limit of 2");
  SubjectInfo long_subject_name = walker_subject();
  long_subject_name.name = "walker78";
  EXPECT_EQ(subject_error(long_subject_name, tight), "SubjectInfo: subject name of 8 bytes exceeds the limit of 7");
  SubjectInfo long_segment_name = walker_subject();
  long_segment_name.segments[0].name = "pelvis78";
  EXPECT_EQ(subject_error(long_segment_name, tight), "SubjectInfo: segment name of 8 bytes exceeds the limit of 7");
  SubjectInfo segments = walker_subject();
  segments.segments.resize(3, segments.segments[0]);
  EXPECT_EQ(subject_error(segments, tight), "SubjectInfo: segment count 3 exceeds the limit of 2");
  SubjectInfo attachments = walker_subject();
  attachments.attachments.resize(3);
  EXPECT_EQ(subject_error(attachments, tight), "SubjectInfo: attachment count 3 exceeds the limit of 2");
}

TEST(ViconLimits, MoreSubjectsInOnePacketThanTheCapAreRejectedByTheSplitAndTheFramer) {
  DescriptionLimits limits;
  limits.max_subjects = 3;
  for (int subjects : {3, 4}) {
    PacketWriter writer;
    writer.add(FrameInfo{1});
    for (int s = 0; s < subjects; ++s) writer.add(walker_subject());
    const ByteVector packet = bytes_of(writer.finish());
    std::vector<ObjectView> objects;
    std::string error;
    const bool split = split_objects(packet, objects, error, limits);
    PacketFramer framer(kMaxPacketLength, limits);
    framer.feed(packet);
    Bytes out;
    const PacketFramer::Status status = framer.next(out);
    if (subjects == 3) {
      EXPECT_TRUE(split) << error;
      EXPECT_EQ(status, PacketFramer::Status::Packet) << framer.error();
    } else {
      EXPECT_FALSE(split);
      EXPECT_EQ(error, "more than 3 SubjectInfo objects in one packet (the limit)");
      EXPECT_EQ(status, PacketFramer::Status::Error);
      EXPECT_EQ(framer.error(), error);
    }
  }
}

TEST(ViconWire, BadHeadersAreRejected) {
  ByteVector bytes = fixture("frame_info.bin");
  bytes[0] = 0x02;
  EXPECT_NE(error_of(bytes).find("bad packet magic 0x1A2B0002"), std::string::npos);
  bytes = fixture("frame_info.bin");
  bytes[12] = 0x40;  // object length 64 in a 12-byte payload
  EXPECT_NE(error_of(bytes).find("overruns the packet"), std::string::npos) << error_of(bytes);
}

TEST(ViconWire, EveryTruncationOfEveryFixtureIsRejected) {
  for (const char* name : {"object_enums.bin", "request_frame_push.bin", "request_frame_pull.bin",
                           "stream_info_120hz.bin", "subject_info.bin", "frame_info.bin", "labeled_recons.bin",
                           "unlabeled_recons.bin", "timecode.bin", "frame_packet.bin"}) {
    const ByteVector whole = fixture(name);
    std::vector<size_t> object_ends = {kPacketHeaderBytes};  // cuts there leave whole objects: valid
    std::vector<ObjectView> objects;
    std::string error;
    ASSERT_TRUE(split_objects(whole, objects, error)) << error;
    for (const ObjectView& o : objects) object_ends.push_back(static_cast<size_t>(o.payload.data() - whole.data()) + o.payload.size());
    for (size_t n = 0; n < whole.size(); ++n) {
      // As a complete packet whose header is made to agree: the cut object no longer fits.
      ByteVector cut(whole.begin(), whole.begin() + static_cast<long>(n));
      if (cut.size() >= 8) {
        const auto length = static_cast<uint32_t>(cut.size() - 8);
        std::memcpy(cut.data() + 4, &length, 4);
      }
      const bool at_object_end = std::find(object_ends.begin(), object_ends.end(), n) != object_ends.end();
      EXPECT_EQ(error_of(cut).empty(), at_object_end) << name << " cut to " << n << " bytes: " << error_of(cut);
      // Unchanged header, cut body: the packet itself is judged truncated.
      ByteVector short_body(whole.begin(), whole.begin() + static_cast<long>(n));
      EXPECT_FALSE(error_of(short_body).empty()) << name << " " << n;
      // As a stream that stops early: the framer waits, never yields a packet.
      PacketFramer framer;
      framer.feed(std::span<const unsigned char>(whole.data(), n));
      Bytes packet;
      EXPECT_EQ(framer.next(packet), PacketFramer::Status::NeedMore) << name << " " << n;
    }
  }
}

TEST(ViconWire, FramerCutsAStreamFedByteByByte) {
  ByteVector stream;
  for (const char* name : {"object_enums.bin", "frame_packet.bin", "timecode.bin"}) {
    const ByteVector f = fixture(name);
    stream.insert(stream.end(), f.begin(), f.end());
  }
  PacketFramer framer;
  std::vector<size_t> sizes;
  for (unsigned char byte : stream) {
    framer.feed(std::span<const unsigned char>(&byte, 1));
    Bytes packet;
    while (framer.next(packet) == PacketFramer::Status::Packet) sizes.push_back(packet.size());
  }
  EXPECT_EQ(sizes, (std::vector<size_t>{52, 359, 33}));
  EXPECT_EQ(framer.buffered(), 0u);
}

// A backlog read in full chunks leaves a partial packet behind most reads; the next prepare()
// then needs the chunk plus that tail. Without reserve() the buffer grows at the first such read
// (on the daemon's io thread, after a stall); reserved for a chunk plus a tail it never does.
TEST(ViconWire, FramerReservedForAReadAndATailNeverGrowsInABacklog) {
  const ByteVector frame = fixture("frame_packet.bin");
  ByteVector backlog;
  for (int i = 0; i < 40; ++i) backlog.insert(backlog.end(), frame.begin(), frame.end());
  constexpr size_t kRead = 1024;  // not a multiple of the 359-byte packet
  auto drain_in_reads = [&](PacketFramer& framer, size_t& most) {
    int packets = 0;
    for (size_t at = 0; at < backlog.size();) {
      const auto room = framer.prepare(kRead);
      const size_t n = std::min(kRead, backlog.size() - at);
      std::memcpy(room.data(), backlog.data() + at, n);
      framer.commit(n);
      at += n;
      most = std::max(most, framer.capacity());
      Bytes packet;
      while (framer.next(packet) == PacketFramer::Status::Packet) ++packets;
    }
    return packets;
  };
  PacketFramer unreserved;
  size_t most = 0;
  EXPECT_EQ(drain_in_reads(unreserved, most), 40);
  EXPECT_GT(most, kRead);  // grew past one read's room

  PacketFramer reserved;
  reserved.reserve(2 * kRead);
  most = 0;
  EXPECT_EQ(drain_in_reads(reserved, most), 40);
  EXPECT_EQ(most, 2 * kRead);
  EXPECT_EQ(reserved.buffered(), 0u);
}

TEST(ViconWire, FramerRejectsBadMagicAndOversizeFromTheHeaderAlone) {
  PacketFramer framer;
  const unsigned char bad_magic[] = {0x47, 0x45, 0x54, 0x20, 0x2F, 0x20, 0x48, 0x54};  // "GET / HT"
  framer.feed(bad_magic);
  Bytes packet;
  EXPECT_EQ(framer.next(packet), PacketFramer::Status::Error);
  EXPECT_NE(framer.error().find("bad packet magic"), std::string::npos);

  PacketFramer framer2;
  const unsigned char huge[] = {0x01, 0x00, 0x2B, 0x1A, 0x01, 0x00, 0x00, 0x01};  // 16 MiB + 1
  framer2.feed(huge);
  EXPECT_EQ(framer2.next(packet), PacketFramer::Status::Error);
  EXPECT_NE(framer2.error().find("exceeds the limit"), std::string::npos) << framer2.error();

  PacketFramer framer3;  // a truncated object header inside a complete packet
  const unsigned char short_object[] = {0x01, 0x00, 0x2B, 0x1A, 0x04, 0x00, 0x00, 0x00, 5, 0, 0, 0};
  framer3.feed(short_object);
  EXPECT_EQ(framer3.next(packet), PacketFramer::Status::Error);
  EXPECT_NE(framer3.error().find("truncated object header"), std::string::npos) << framer3.error();
}

TEST(ViconWire, RandomCorruptionNeverCrashes) {
  std::vector<ByteVector> seeds;
  for (const char* name : {"object_enums.bin", "subject_info.bin", "labeled_recons.bin", "unlabeled_recons.bin",
                           "timecode.bin", "frame_packet.bin"})
    seeds.push_back(fixture(name));
  std::mt19937 rng(20261122);
  int accepted = 0, rejected = 0;
  PacketFramer framer;
  for (int trial = 0; trial < 5000; ++trial) {
    ByteVector bytes = seeds[static_cast<size_t>(trial) % seeds.size()];
    const int flips = 1 + static_cast<int>(rng() % 6);
    for (int f = 0; f < flips; ++f) {
      const size_t at = rng() % bytes.size();
      switch (rng() % 3) {
        case 0: bytes[at] = static_cast<unsigned char>(rng()); break;
        case 1: bytes[at] ^= static_cast<unsigned char>(1u << (rng() % 8)); break;
        default: bytes[at] = (rng() % 2) ? 0xFF : 0x00; break;
      }
    }
    // Whole-packet decoding and the framer both survive and agree on the header checks.
    DecodedPacket d;
    std::string error;
    if (decode_packet(bytes, d, error)) {
      ++accepted;
    } else {
      ++rejected;
      EXPECT_FALSE(error.empty());
      EXPECT_EQ(error.find('\n'), std::string::npos);
    }
    framer.reset();
    framer.feed(bytes);
    Bytes packet;
    const auto status = framer.next(packet);
    if (status == PacketFramer::Status::Packet) {
      std::vector<LabeledRecon> labelled;
      for (const ObjectView& o : framer.objects())
        if (o.type == object_type::LabeledRecons) decode(o.payload, labelled, error);
    }
  }
  EXPECT_GT(rejected, 1000);  // corruption is mostly caught
  EXPECT_GT(accepted, 0);     // flips inside doubles are valid packets
}

}  // namespace
}  // namespace skinstream::vicon
