#include "protocol/subscriber/subscriber_stream.h"

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <random>

#include "support/subscriber_fixture.h"
#include "support/test_data.h"

namespace skinstream::subscriber {
namespace {

using test::payload_of;
using test::subscriber_fixture;

const std::vector<float> kPositions = {0, 100, 5, 65535, 131170, 5, 0, 2100, 5};
const std::vector<float> kNormals = {1, 0, 0, 0, -1, 0, 0, 0, 1};
const std::vector<float> kMarkers = {1.5f, 2.5f, 3.5f, -4.0f, 5.0f, 6.25f};
const std::vector<uint8_t> kStatus = {0, 2};

FrameInfo fixture_info(uint32_t flags, uint32_t vertex_count) {
  FrameInfo info;
  info.frame_number = 1234;
  info.flags = flags;
  info.source_time_ns = 10'000'000;
  info.receive_time_ns = 1'700'000'000'000'000'000;
  info.publish_time_ns = 1'700'000'000'001'000'000;
  info.vertex_count = vertex_count;
  info.marker_count = 2;
  info.markers_filled = 3;
  info.markers_relabelled = 1;
  info.pipeline_dropped = 7;
  info.subscriber_dropped = 2;
  return info;
}

std::vector<unsigned char> encode(const FrameInfo& info) {
  std::vector<unsigned char> out(frame_message_bytes(info.flags, info.vertex_count, info.marker_count));
  encode_frame(info, kPositions, kNormals, kMarkers, kStatus, out);
  return out;
}

MeshInfo fixture_mesh_info() {
  MeshInfo info;
  info.vertex_count = 4;
  info.marker_count = 3;
  info.part_count = 2;
  info.source_rate_hz = 120.0f;
  info.faces = {{0, 1, 2}, {0, 2, 3}};
  info.dominant_part = {0, 1, 255, 1};
  info.marker_triangles = {{0, 1, 2}};
  info.marker_names = {"LSHO", "RSHO", "C7"};
  return info;
}

TEST(SubscriberStream, HeaderRejectsBadMagicVersionTypeAndSize) {
  std::vector<unsigned char> good = subscriber_fixture("hello.bin");
  EXPECT_NO_THROW(decode_header(good));
  auto expect_reject = [&](size_t at, unsigned char value, const char* reason) {
    std::vector<unsigned char> bad = good;
    bad[at] = value;
    try {
      decode_header(bad);
      FAIL() << "accepted a header with " << reason;
    } catch (const DecodeError& e) {
      EXPECT_NE(std::string(e.what()).find(reason), std::string::npos) << e.what();
    }
  };
  expect_reject(0, 'X', "bad magic");
  expect_reject(4, 3, "version 3");
  expect_reject(6, 9, "unknown message type 9");
  expect_reject(6, 6, "unknown message type 6 in version 1");  // Model is version 2's
  expect_reject(11, 0x10, "exceeds the limit");
  EXPECT_THROW(decode_header(std::span(good).first(11)), DecodeError);
}

TEST(SubscriberStream, HelloMatchesGoldenBytes) {
  EXPECT_EQ(encode_hello({.wants = kWantNormals | kWantMarkers}), subscriber_fixture("hello.bin"));
  EXPECT_EQ(decode_hello(payload_of(subscriber_fixture("hello.bin"))).wants, kWantNormals | kWantMarkers);
  const std::vector<unsigned char> reserved = encode_hello({.wants = 0x20});
  EXPECT_THROW(decode_hello(payload_of(reserved)), DecodeError);
  EXPECT_EQ(decode_hello(payload_of(encode_hello({.wants = kWantPaced}))).wants, kWantPaced);
}

// ack.bin was written with Python's struct: b'SKSF' + pack('<HHI', 1, 5, 4) + pack('<I', 123456).
TEST(SubscriberStream, AckMatchesGoldenBytes) {
  EXPECT_EQ(encode_ack({123456}), subscriber_fixture("ack.bin"));
  const std::vector<unsigned char> golden = subscriber_fixture("ack.bin");
  EXPECT_EQ(decode_header(golden).type, MessageType::Ack);
  EXPECT_EQ(decode_ack(payload_of(golden)).frame_number, 123456u);
}

TEST(SubscriberStream, MeshInfoMatchesGoldenBytes) {
  const std::vector<unsigned char> golden = subscriber_fixture("mesh_info.bin");
  EXPECT_EQ(encode_mesh_info(fixture_mesh_info()), golden);
  const MeshInfo decoded = decode_mesh_info(payload_of(golden));
  EXPECT_EQ(decoded.vertex_count, 4u);
  EXPECT_EQ(decoded.faces, fixture_mesh_info().faces);
  EXPECT_EQ(decoded.dominant_part, fixture_mesh_info().dominant_part);
  EXPECT_EQ(decoded.marker_triangles, fixture_mesh_info().marker_triangles);
  EXPECT_EQ(decoded.marker_names, fixture_mesh_info().marker_names);
  EXPECT_EQ(decoded.source_rate_hz, 120.0f);
}

TEST(SubscriberStream, MeshInfoRejectsOutOfRangeIndices) {
  MeshInfo info = fixture_mesh_info();
  info.faces[1][2] = 4;
  EXPECT_THROW(decode_mesh_info(payload_of(encode_mesh_info(info))), DecodeError);
  info = fixture_mesh_info();
  info.marker_triangles[0][0] = 3;
  EXPECT_THROW(decode_mesh_info(payload_of(encode_mesh_info(info))), DecodeError);
}

TEST(SubscriberStream, FloatFrameMatchesGoldenBytes) {
  const std::vector<unsigned char> golden = subscriber_fixture("frame_float.bin");
  EXPECT_EQ(encode(fixture_info(kFrameNormals | kFrameMarkers, 3)), golden);
  const Frame frame = decode_frame(payload_of(golden));
  EXPECT_EQ(frame.info.frame_number, 1234u);
  EXPECT_EQ(frame.info.receive_time_ns, 1'700'000'000'000'000'000);
  EXPECT_EQ(frame.info.publish_time_ns, 1'700'000'000'001'000'000);
  EXPECT_EQ(frame.info.markers_filled, 3);
  EXPECT_EQ(frame.info.pipeline_dropped, 7u);
  EXPECT_EQ(frame.info.subscriber_dropped, 2u);
  EXPECT_EQ(frame.positions, kPositions);
  EXPECT_EQ(frame.normals, kNormals);
  EXPECT_EQ(frame.markers, kMarkers);
  EXPECT_EQ(frame.marker_status, kStatus);
}

TEST(SubscriberStream, QuantisedFrameMatchesGoldenBytes) {
  const std::vector<unsigned char> golden = subscriber_fixture("frame_quantised.bin");
  EXPECT_EQ(encode(fixture_info(kFrameNormals | kFrameMarkers | kFrameQuantised, 3)), golden);
  const Frame frame = decode_frame(payload_of(golden));
  EXPECT_EQ(frame.positions, kPositions);  // this fixture's values are exact on the grid
  EXPECT_EQ(frame.normals, kNormals);
  EXPECT_EQ(frame.step[1], 2.0f);
}

TEST(SubscriberStream, MarkersOnlyFrameMatchesGoldenBytes) {
  const std::vector<unsigned char> golden = subscriber_fixture("frame_markers_only.bin");
  EXPECT_EQ(encode(fixture_info(kFrameNoPositions | kFrameMarkers, 0)), golden);
  const Frame frame = decode_frame(payload_of(golden));
  EXPECT_TRUE(frame.positions.empty());
  EXPECT_EQ(frame.markers, kMarkers);
}

TEST(SubscriberStream, EveryFrameBlockStaysFourByteAligned) {
  // Receivers view blocks in place (JavaScript Float32Array needs offsets that are multiples of 4).
  for (uint32_t flags = 0; flags < 16; ++flags)
    for (uint32_t v : {1u, 2u, 3u, 5u})
      for (uint32_t m : {1u, 2u, 3u})
        EXPECT_EQ(frame_message_bytes(flags, v, m) % 4, 0u) << flags << " " << v << " " << m;
}

TEST(SubscriberStream, StatusMatchesGoldenBytes) {
  const Status status{.state = SourceStateCode::Disconnected, .source_rate_hz = 119.88f, .frames_received = 1000, .frames_published = 990,
                      .detail = "vicon 127.0.0.1:801: connection refused"};
  const std::vector<unsigned char> golden = subscriber_fixture("status.bin");
  EXPECT_EQ(encode_status(status), golden);
  const Status decoded = decode_status(payload_of(golden));
  EXPECT_EQ(decoded.state, SourceStateCode::Disconnected);
  EXPECT_EQ(decoded.frames_received, 1000u);
  EXPECT_EQ(decoded.frames_published, 990u);
  EXPECT_EQ(decoded.detail, status.detail);
}

TEST(SubscriberStream, PatchingSubscriberDropsChangesOnlyThatField) {
  std::vector<unsigned char> message = subscriber_fixture("frame_float.bin");
  patch_subscriber_dropped(message, 99);
  EXPECT_EQ(decode_frame(payload_of(message)).info.subscriber_dropped, 99u);
  patch_subscriber_dropped(message, 2);
  EXPECT_EQ(message, subscriber_fixture("frame_float.bin"));
}

TEST(SubscriberStream, PatchingThePublishTimeChangesOnlyThatField) {
  const std::vector<unsigned char> original = subscriber_fixture("frame_quantised.bin");
  const FrameInfo before = decode_frame(payload_of(original)).info;
  std::vector<unsigned char> message = original;
  patch_publish_time(message, 1'800'000'000'123'456'789);
  const Frame patched = decode_frame(payload_of(message));
  EXPECT_EQ(patched.info.publish_time_ns, 1'800'000'000'123'456'789);
  EXPECT_EQ(patched.info.receive_time_ns, before.receive_time_ns);
  EXPECT_EQ(patched.info.vertex_count, before.vertex_count);
  patch_publish_time(message, before.publish_time_ns);
  EXPECT_EQ(message, original);
  std::vector<unsigned char> too_short(kPublishTimeOffset + 7);
  EXPECT_THROW(patch_publish_time(too_short, 1), std::invalid_argument);
}

TEST(SubscriberStream, FlagsFollowWants) {
  EXPECT_EQ(frame_flags_for(0, true), 0u);
  EXPECT_EQ(frame_flags_for(kWantNormals | kWantQuantised, true), kFrameNormals | kFrameQuantised);
  EXPECT_EQ(frame_flags_for(kWantNormals, false), kFrameNoPositions);
  EXPECT_EQ(frame_flags_for(kWantNoMesh | kWantMarkers, true), kFrameNoPositions | kFrameMarkers);
}

TEST(SubscriberStream, EveryTruncationOfEveryMessageIsRejected) {
  for (const char* name : {"hello.bin", "ack.bin", "mesh_info.bin", "frame_float.bin", "frame_quantised.bin", "frame_markers_only.bin",
                           "status.bin", "hello_v2.bin", "mesh_info_v2.bin", "status_v2.bin", "frame_v2_float.bin",
                           "frame_v2_parameters.bin", "frame_v2_compressed.bin"}) {
    const std::vector<unsigned char> message = subscriber_fixture(name);
    const MessageHeader header = decode_header(message);
    const uint16_t v = header.version;
    for (size_t n = kHeaderBytes; n < message.size(); ++n) {
      const std::span<const unsigned char> cut = std::span(message).subspan(kHeaderBytes, n - kHeaderBytes);
      auto decode = [&] {
        switch (header.type) {
          case MessageType::Hello: decode_hello(cut, v); break;
          case MessageType::Ack: decode_ack(cut); break;
          case MessageType::MeshInfo: decode_mesh_info(cut, v); break;
          case MessageType::Frame: decode_frame(cut, v); break;
          case MessageType::Status: decode_status(cut, v); break;
          case MessageType::Model:
          case MessageType::Packed:
            FAIL() << "no decoder of it here";
            break;
        }
      };
      EXPECT_THROW(decode(), DecodeError) << name << " cut at " << n;
      if (header.type == MessageType::Frame) {
        EXPECT_THROW(decode_frame_info(cut, v), DecodeError) << name << " cut at " << n;
      }
    }
    // A byte too many is refused as well.
    std::vector<unsigned char> longer(message.begin() + kHeaderBytes, message.end());
    longer.push_back(0);
    if (header.type == MessageType::Frame) {
      EXPECT_THROW(decode_frame(longer, v), DecodeError) << name;
      EXPECT_THROW(decode_frame_info(longer, v), DecodeError) << name;
    }
    if (header.type == MessageType::Hello) { EXPECT_THROW(decode_hello(longer, v), DecodeError) << name; }
    if (header.type == MessageType::Status) { EXPECT_THROW(decode_status(longer, v), DecodeError) << name; }
    if (header.type == MessageType::MeshInfo) { EXPECT_THROW(decode_mesh_info(longer, v), DecodeError) << name; }
  }
}

// ---- version 2 (the golden files come from make_v2_fixtures.py, written from the spec) ----

TEST(SubscriberStreamV2, HelloMatchesGoldenBytes) {
  Hello hello;
  hello.version = kVersion2;
  hello.wants = kWantNormals | kWantMarkers | kWantPaced;
  hello.encoding = static_cast<uint32_t>(Encoding::Parameters);
  hello.subject = "Actor2";
  hello.token = "stage-token";
  const std::vector<unsigned char> golden = subscriber_fixture("hello_v2.bin");
  EXPECT_EQ(encode_hello(hello), golden);
  const MessageHeader header = decode_header(golden);
  EXPECT_EQ(header.version, kVersion2);
  const Hello decoded = decode_hello(payload_of(golden), header.version);
  EXPECT_EQ(decoded.wants, hello.wants);
  EXPECT_EQ(decoded.encoding, hello.encoding);
  EXPECT_EQ(decoded.subject, "Actor2");
  EXPECT_EQ(decoded.token, "stage-token");
  // The version 1 payload is not a version 2 Hello, nor the other way round.
  EXPECT_THROW(decode_hello(payload_of(golden), kVersion1), DecodeError);
  EXPECT_THROW(decode_hello(payload_of(subscriber_fixture("hello.bin")), kVersion2), DecodeError);
}

TEST(SubscriberStreamV2, HelloKeepsAnUnknownEncodingAndRefusesTheQuantisedBitAndLongNames) {
  Hello hello;
  hello.version = kVersion2;
  hello.encoding = 7;
  EXPECT_EQ(decode_hello(payload_of(encode_hello(hello)), kVersion2).encoding, 7u);  // the daemon answers it
  hello.wants = kWantQuantised;  // version 2 says the encoding apart
  EXPECT_THROW(decode_hello(payload_of(encode_hello(hello)), kVersion2), DecodeError);
  // A longer subject is cut by the encoder; a decoder refuses one over the limit.
  std::vector<unsigned char> payload = {0, 0, 0, 0, 0, 0, 0, 0};
  const uint16_t n = kMaxHelloString + 1;
  payload.push_back(static_cast<unsigned char>(n & 0xFF));
  payload.push_back(static_cast<unsigned char>(n >> 8));
  payload.resize(payload.size() + n + 2, 'a');
  try {
    decode_hello(payload, kVersion2);
    FAIL() << "accepted a subject of " << n << " bytes";
  } catch (const DecodeError& e) {
    EXPECT_NE(std::string(e.what()).find("subject name of 257 bytes exceeds 256"), std::string::npos) << e.what();
  }
}

TEST(SubscriberStreamV2, MeshInfoMatchesGoldenBytes) {
  MeshInfo info = fixture_mesh_info();
  info.subject = "Actor2";
  info.encoding = Encoding::Compressed;
  info.compressed_order = {2, 0, 3, 1};
  const std::vector<unsigned char> golden = subscriber_fixture("mesh_info_v2.bin");
  EXPECT_EQ(encode_mesh_info(info, kVersion2), golden);
  const MeshInfo decoded = decode_mesh_info(payload_of(golden), kVersion2);
  EXPECT_EQ(decoded.faces, info.faces);
  EXPECT_EQ(decoded.marker_names, info.marker_names);
  EXPECT_EQ(decoded.subject, "Actor2");
  EXPECT_EQ(decoded.encoding, Encoding::Compressed);
  EXPECT_EQ(decoded.compressed_order, info.compressed_order);
  // Version 1's MeshInfo is the same bytes without the two version 2 fields.
  const std::vector<unsigned char> v1 = subscriber_fixture("mesh_info.bin");
  EXPECT_TRUE(std::equal(v1.begin() + kHeaderBytes, v1.end(), golden.begin() + kHeaderBytes));
  std::vector<unsigned char> bad = golden;
  bad[bad.size() - 24] = 4;  // encoding 4 does not exist
  EXPECT_THROW(decode_mesh_info(payload_of(bad), kVersion2), DecodeError);
  bad = golden;
  bad[bad.size() - 4] = 4;  // the order names vertex 4 of 4
  EXPECT_THROW(decode_mesh_info(payload_of(bad), kVersion2), DecodeError);
  bad = golden;
  bad[bad.size() - 20] = 3;  // an order of 3 for 4 vertices
  EXPECT_THROW(decode_mesh_info(payload_of(bad), kVersion2), DecodeError);
}

TEST(SubscriberStreamV2, StatusMatchesGoldenBytesAndRefusalReadsAsDisconnectedInVersion1) {
  Status status{.state = SourceStateCode::Refused, .frames_received = 10, .frames_published = 9,
                .detail = "no subject \"Actor3\" (subjects: Actor1, Actor2)"};
  status.subject = "Actor3";
  status.subject_present = false;
  const std::vector<unsigned char> golden = subscriber_fixture("status_v2.bin");
  EXPECT_EQ(encode_status(status, kVersion2), golden);
  const Status decoded = decode_status(payload_of(golden), kVersion2);
  EXPECT_EQ(decoded.state, SourceStateCode::Refused);
  EXPECT_EQ(decoded.detail, status.detail);
  EXPECT_EQ(decoded.subject, "Actor3");
  EXPECT_FALSE(decoded.subject_present);
  const Status v1 = decode_status(payload_of(encode_status(status, kVersion1)), kVersion1);
  EXPECT_EQ(v1.state, SourceStateCode::Disconnected);
  EXPECT_EQ(v1.detail, status.detail);
  EXPECT_THROW(decode_status(payload_of(golden), kVersion1), DecodeError);  // state 4 and trailing fields
}

FrameInfo fixture_info_v2(uint32_t flags, uint32_t vertex_count) {
  FrameInfo info = fixture_info(flags, vertex_count);
  if (flags & kFrameTimecode) info.timecode = {10, 20, 30, 12, 1, 5, 29.97f, kTimecodeDropFrame};
  return info;
}

TEST(SubscriberStreamV2, FloatFrameWithTimecodeMatchesGoldenBytes) {
  const FrameInfo info = fixture_info_v2(kFrameMarkers | kFrameTimecode, 3);
  std::vector<unsigned char> out(frame_message_bytes(info.flags, info.vertex_count, info.marker_count, kVersion2));
  encode_frame(info, kPositions, {}, kMarkers, kStatus, out, kVersion2);
  const std::vector<unsigned char> golden = subscriber_fixture("frame_v2_float.bin");
  EXPECT_EQ(out, golden);
  const Frame frame = decode_frame(payload_of(golden), kVersion2);
  EXPECT_EQ(frame.positions, kPositions);
  EXPECT_EQ(frame.markers, kMarkers);
  EXPECT_EQ(frame.marker_status, kStatus);
  EXPECT_EQ(frame.info.timecode.hours, 10);
  EXPECT_EQ(frame.info.timecode.frames, 12);
  EXPECT_EQ(frame.info.timecode.subframes_per_frame, 5);
  EXPECT_EQ(frame.info.timecode.rate_hz, 29.97f);
  EXPECT_EQ(frame.info.timecode.flags, kTimecodeDropFrame);
  // Both versions keep the fields the daemon patches per subscriber at the same offsets.
  std::vector<unsigned char> patched = golden;
  patch_subscriber_dropped(patched, 41);
  patch_publish_time(patched, 5);
  const FrameInfo read = decode_frame_info(payload_of(patched), kVersion2);
  EXPECT_EQ(read.subscriber_dropped, 41u);
  EXPECT_EQ(read.publish_time_ns, 5);
  EXPECT_THROW(decode_frame(payload_of(golden), kVersion1), DecodeError);
}

// The framing of blocks coded elsewhere: the bytes after the fixed part are passed through.
void expect_block_frame_matches(const char* name, uint32_t flags, uint32_t vertex_count, size_t block_bytes) {
  const std::vector<unsigned char> golden = subscriber_fixture(name);
  FrameInfo info = fixture_info_v2(flags, vertex_count);
  if (!(flags & kFrameMarkers)) info.marker_count = 0;
  const size_t block_at = kHeaderBytes + frame_info_bytes(kVersion2);
  const std::span<const unsigned char> block = std::span(golden).subspan(block_at, block_bytes);
  std::vector<unsigned char> out(frame_message_bytes_with_block(block.size(), flags, info.marker_count));
  encode_frame_with_block(info, block, kMarkers, kStatus, out);
  EXPECT_EQ(out, golden) << name;
  const FrameView view = view_frame(payload_of(golden), kVersion2);
  EXPECT_EQ(view.info.flags, flags) << name;
  EXPECT_EQ(view.positions.size() + view.normals.size(), block_bytes) << name;
  EXPECT_EQ(view.positions.data(), golden.data() + block_at) << name;
  const Frame frame = decode_frame(payload_of(golden), kVersion2);
  EXPECT_TRUE(frame.positions.empty()) << name;
  EXPECT_EQ(frame.coded_positions.size(), view.positions.size()) << name;
  EXPECT_EQ(frame.coded_normals.size(), view.normals.size()) << name;
}

TEST(SubscriberStreamV2, ParameterFrameFraming) {
  expect_block_frame_matches("frame_v2_parameters.bin", kFrameMarkers | kFrameParameters, 0, 8 + 160 + 24);
  const Frame frame = decode_frame(payload_of(subscriber_fixture("frame_v2_parameters.bin")), kVersion2);
  EXPECT_EQ(frame.markers, kMarkers);
}

TEST(SubscriberStreamV2, CompressedFrameFraming) {
  expect_block_frame_matches("frame_v2_compressed.bin", kFrameNormals | kFrameCompressed | kFrameKey, 3, 40 + 12);
  const FrameView view = view_frame(payload_of(subscriber_fixture("frame_v2_compressed.bin")), kVersion2);
  EXPECT_EQ(view.positions.size(), 40u);  // key, origin, step, count, 7 bytes padded to 8
  EXPECT_EQ(view.normals.size(), 12u);    // count, 5 bytes padded to 8
}

TEST(SubscriberStreamV2, InconsistentFlagsAreRejected) {
  const std::vector<unsigned char> golden = subscriber_fixture("frame_v2_parameters.bin");
  auto with_flags = [&](uint32_t flags) {
    std::vector<unsigned char> bad(golden.begin() + kHeaderBytes, golden.end());
    std::memcpy(bad.data() + 4, &flags, 4);
    return bad;
  };
  EXPECT_THROW(view_frame(with_flags(kFrameMarkers | kFrameParameters | kFrameQuantised), kVersion2), DecodeError);
  EXPECT_THROW(view_frame(with_flags(kFrameMarkers | kFrameParameters | kFrameNormals), kVersion2), DecodeError);
  EXPECT_THROW(view_frame(with_flags(kFrameMarkers | kFrameParameters | kFrameKey), kVersion2), DecodeError);
  EXPECT_THROW(view_frame(with_flags(kFrameMarkers | kFrameParameters | kFrameNoPositions), kVersion2), DecodeError);
  EXPECT_THROW(view_frame(with_flags(kFrameMarkers | kFrameParameters | 0x100), kVersion2), DecodeError);
  // A part count that claims more than the payload holds.
  std::vector<unsigned char> bad(golden.begin() + kHeaderBytes, golden.end());
  const uint32_t parts = 1'000'000;
  std::memcpy(bad.data() + frame_info_bytes(kVersion2), &parts, 4);
  EXPECT_THROW(view_frame(bad, kVersion2), DecodeError);
}

TEST(SubscriberStreamV2, FlagsFollowWantsAndEncoding) {
  EXPECT_EQ(frame_flags_for(kWantNormals, Encoding::Float, true), kFrameNormals);
  EXPECT_EQ(frame_flags_for(kWantNormals | kWantMarkers, Encoding::Parameters, true), kFrameParameters | kFrameMarkers);
  EXPECT_EQ(frame_flags_for(kWantNormals, Encoding::Compressed, true), kFrameNormals | kFrameCompressed);
  EXPECT_EQ(frame_flags_for(kWantNormals, Encoding::Quantised, true), kFrameNormals | kFrameQuantised);
  EXPECT_EQ(frame_flags_for(kWantNormals, Encoding::Parameters, false), kFrameNoPositions);
  EXPECT_EQ(frame_flags_for(kWantNoMesh | kWantMarkers, Encoding::Compressed, true), kFrameNoPositions | kFrameMarkers);
}

TEST(SubscriberStream, CorruptFrameCountsAndFlagsAreRejected) {
  const std::vector<unsigned char> golden = subscriber_fixture("frame_float.bin");
  auto corrupt = [&](size_t payload_offset, uint32_t value) {
    std::vector<unsigned char> bad(golden.begin() + kHeaderBytes, golden.end());
    std::memcpy(bad.data() + payload_offset, &value, 4);
    return bad;
  };
  EXPECT_THROW(decode_frame(corrupt(32, 1'000'000'000)), DecodeError);  // vertex count
  EXPECT_THROW(decode_frame(corrupt(36, 0xFFFFFFFF)), DecodeError);     // marker count
  EXPECT_THROW(decode_frame(corrupt(4, 0x10)), DecodeError);            // reserved flag
  for (const auto& [offset, value] : {std::pair<size_t, uint32_t>{32, 1'000'000'000}, {36, 0xFFFFFFFF}, {4, 0x10}})
    EXPECT_THROW(decode_frame_info(corrupt(offset, value)), DecodeError) << "offset " << offset;
  std::vector<unsigned char> bad_status(golden.begin() + kHeaderBytes, golden.end());
  bad_status[bad_status.size() - 4] = 9;  // first marker status byte
  EXPECT_THROW(decode_frame(bad_status), DecodeError);
}

TEST(SubscriberStream, StreamDecoderCutsMessagesAtAnyBoundary) {
  std::vector<unsigned char> stream;
  for (const char* name : {"status.bin", "mesh_info.bin", "frame_float.bin", "frame_quantised.bin"}) {
    const std::vector<unsigned char> m = subscriber_fixture(name);
    stream.insert(stream.end(), m.begin(), m.end());
  }
  for (size_t chunk : {size_t{1}, size_t{5}, size_t{13}, stream.size()}) {
    StreamDecoder decoder;
    std::vector<MessageType> types;
    for (size_t at = 0; at < stream.size(); at += chunk) {
      decoder.feed(std::span(stream).subspan(at, std::min(chunk, stream.size() - at)));
      while (auto message = decoder.next()) {
        types.push_back(message->type);
        if (message->type == MessageType::Frame) {
          EXPECT_EQ(decode_frame(message->payload).info.frame_number, 1234u);
        }
      }
    }
    EXPECT_EQ(types, (std::vector<MessageType>{MessageType::Status, MessageType::MeshInfo, MessageType::Frame, MessageType::Frame}))
        << "chunk " << chunk;
    EXPECT_EQ(decoder.buffered(), 0u);
  }
}

TEST(SubscriberStream, FrameInfoAloneMatchesTheWholeDecode) {
  for (const char* name : {"frame_float.bin", "frame_quantised.bin", "frame_markers_only.bin"}) {
    const std::vector<unsigned char> message = subscriber_fixture(name);
    const std::span<const unsigned char> payload = std::span(message).subspan(kHeaderBytes);
    const FrameInfo whole = decode_frame(payload).info, alone = decode_frame_info(payload);
    EXPECT_EQ(alone.frame_number, whole.frame_number) << name;
    EXPECT_EQ(alone.flags, whole.flags) << name;
    EXPECT_EQ(alone.source_time_ns, whole.source_time_ns) << name;
    EXPECT_EQ(alone.receive_time_ns, whole.receive_time_ns) << name;
    EXPECT_EQ(alone.publish_time_ns, whole.publish_time_ns) << name;
    EXPECT_EQ(alone.vertex_count, whole.vertex_count) << name;
    EXPECT_EQ(alone.marker_count, whole.marker_count) << name;
    EXPECT_EQ(alone.markers_filled, whole.markers_filled) << name;
    EXPECT_EQ(alone.markers_relabelled, whole.markers_relabelled) << name;
    EXPECT_EQ(alone.pipeline_dropped, whole.pipeline_dropped) << name;
    EXPECT_EQ(alone.subscriber_dropped, whole.subscriber_dropped) << name;
  }
}

// As a socket reader uses it: room for more than arrives, a short read, the rest later.
TEST(SubscriberStream, StreamDecoderTakesReadsStraightIntoItsBuffer) {
  std::vector<unsigned char> stream;
  for (int repeat = 0; repeat < 3; ++repeat)
    for (const char* name : {"status.bin", "frame_float.bin", "mesh_info.bin", "frame_quantised.bin"}) {
      const std::vector<unsigned char> m = subscriber_fixture(name);
      stream.insert(stream.end(), m.begin(), m.end());
    }
  for (size_t read_bytes : {size_t{1}, size_t{7}, size_t{100}, stream.size()}) {
    StreamDecoder decoder;
    int frames = 0, messages = 0;
    for (size_t at = 0; at < stream.size();) {
      const std::span<unsigned char> room = decoder.prepare(2 * read_bytes + 3);
      ASSERT_GE(room.size(), 2 * read_bytes + 3);
      const size_t n = std::min(read_bytes, stream.size() - at);
      std::copy_n(stream.begin() + static_cast<std::ptrdiff_t>(at), n, room.begin());
      decoder.commit(n);
      at += n;
      while (auto message = decoder.next()) {
        ++messages;
        if (message->type == MessageType::Frame) {
          EXPECT_EQ(decode_frame(message->payload).info.frame_number, 1234u);
          ++frames;
        }
      }
    }
    EXPECT_EQ(messages, 12) << "reads of " << read_bytes;
    EXPECT_EQ(frames, 6) << "reads of " << read_bytes;
    EXPECT_EQ(decoder.buffered(), 0u);
  }
}

TEST(SubscriberStream, StreamDecoderRejectsGarbageAndOversizedPayloads) {
  StreamDecoder decoder(1024);
  const std::vector<unsigned char> garbage = {'G', 'E', 'T', ' ', '/', ' ', 'H', 'T', 'T', 'P', '/', '1'};
  decoder.feed(garbage);
  EXPECT_THROW(decoder.next(), DecodeError);

  StreamDecoder small(16);
  small.feed(subscriber_fixture("mesh_info.bin"));  // 80-byte payload
  EXPECT_THROW(small.next(), DecodeError);
}

TEST(SubscriberStream, QuantisedPositionsAreWithinHalfAStep) {
  std::mt19937 random(7);
  std::uniform_real_distribution<float> coordinate(-1500.0f, 1800.0f);
  std::normal_distribution<float> component(0.0f, 1.0f);
  const uint32_t v = 2000;
  std::vector<float> positions(3 * v), normals(3 * v);
  for (float& x : positions) x = coordinate(random);
  for (uint32_t i = 0; i < v; ++i) {
    Eigen::Vector3f n(component(random), component(random), component(random));
    n.normalize();
    for (int a = 0; a < 3; ++a) normals[3 * i + a] = n[a];
  }
  FrameInfo info;
  info.flags = kFrameQuantised | kFrameNormals;
  info.vertex_count = v;
  std::vector<unsigned char> message(frame_message_bytes(info.flags, v, 0));
  encode_frame(info, positions, normals, {}, {}, message);
  EXPECT_LT(message.size(), frame_message_bytes(kFrameNormals, v, 0) / 2 + 100);  // halves the bytes
  const Frame frame = decode_frame(payload_of(message));
  for (size_t i = 0; i < positions.size(); ++i) {
    const float half_step = 0.5f * frame.step[i % 3];
    ASSERT_LE(std::abs(frame.positions[i] - positions[i]), half_step * 1.001f + 1e-4f) << i;
    ASSERT_LE(std::abs(frame.normals[i] - normals[i]), 0.5f / 32767.0f + 1e-6f) << i;
  }
}

}  // namespace
}  // namespace skinstream::subscriber
