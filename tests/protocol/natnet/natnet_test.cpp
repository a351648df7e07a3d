// NatNet messages (protocol/natnet_reader, _writer, _capture_encoder) against golden fixtures
// written independently of the writer (tests/protocol/fixtures/natnet/make_fixtures.py packs each
// message with Python's struct from the NatNet packet description), in the 3.1, 4.0 and 4.1
// layouts, and bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

#include "protocol/natnet/natnet_capture_encoder.h"
#include "protocol/natnet/natnet_reader.h"
#include "protocol/natnet/natnet_writer.h"
#include "support/allocation_counter.h"
#include "support/fixture_bytes.h"

namespace skinstream::natnet {
namespace {

using test::bytes_of;

constexpr Version k31{3, 1}, k40{4, 0}, k41{4, 1};

ByteVector fixture(const std::string& name) { return test::fixture_bytes("natnet/" + name); }

Bytes payload_of(const ByteVector& datagram, uint16_t expected_id) {
  uint16_t id = 0;
  Bytes payload;
  std::string error;
  EXPECT_TRUE(read_message(datagram, id, payload, error)) << error;
  EXPECT_EQ(id, expected_id);
  return payload;
}

// The walker take of the fixtures: LASI, RASI, *7 at 120 Hz from frame 10; index 1 has RASI missing.
Capture walker_capture() {
  Capture c({"LASI", "RASI", "*7"}, 2, 120.0);
  c.first_frame = 10;
  c.at(0, 0) = Vec3(1, 2, 3);
  c.at(0, 1) = Vec3(4, 5, 6);
  c.at(0, 2) = Vec3(7, 8, 9);
  c.at(1, 0) = Vec3(100.5, -200.25, 950.125);
  c.at(1, 1) = missing_point();
  c.at(1, 2) = Vec3(1, 2, 3);
  return c;
}

FrameOfData decoded_frame(const ByteVector& datagram, Version version) {
  FrameOfData frame;
  std::string error;
  EXPECT_TRUE(decode_frame(payload_of(datagram, message::FrameOfData), version, frame, error)) << error;
  return frame;
}

std::string error_of(const ByteVector& datagram, Version version) {
  Message m;
  std::string error;
  EXPECT_FALSE(decode_message(datagram, version, m, error)) << "accepted a bad message";
  EXPECT_EQ(error.find('\n'), std::string::npos) << error;
  return error;
}

void put_i32(ByteVector& bytes, size_t offset, int32_t value) { std::memcpy(bytes.data() + offset, &value, 4); }

// Motive stamps each frame at its cameras' mid-exposure and as it transmits, in the ticks of the
// clock ServerInfo names: their difference is the system's own latency.
TEST(NatNet, TheCaptureLatencyIsTransmitMinusMidExposureInTheServersClock) {
  FrameOfData frame;
  frame.stamp_mid_exposure = 10'000'000;
  frame.stamp_transmit = 10'045'000;  // 45,000 ticks of a 10 MHz clock: 4.5 ms
  EXPECT_EQ(capture_latency_ns(frame, 10'000'000), 4'500'000);
  EXPECT_EQ(capture_latency_ns(frame, 0), -1);  // no clock: nothing to say
  frame.stamp_transmit = frame.stamp_mid_exposure - 1;
  EXPECT_EQ(capture_latency_ns(frame, 10'000'000), -1);  // not monotonic
  frame.stamp_transmit = frame.stamp_mid_exposure + 10'000'001;
  EXPECT_EQ(capture_latency_ns(frame, 10'000'000), -1);  // over a second: no latency
  frame.stamp_mid_exposure = frame.stamp_transmit = 0;
  EXPECT_EQ(capture_latency_ns(frame, 10'000'000), -1);  // a server that leaves them 0
}

TEST(NatNet, KeepAliveAndRequestsAreSpelledOutByHand) {
  EXPECT_EQ(encode_empty(message::KeepAlive), (ByteVector{0x0A, 0x00, 0x00, 0x00}));  // u16 id 10, u16 0 bytes
  EXPECT_EQ(fixture("keep_alive.bin"), encode_empty(message::KeepAlive));
  EXPECT_EQ(fixture("request_model_def.bin"), encode_empty(message::RequestModelDef));
  // A NUL after an empty request (as NatNet's Python client sends it) is tolerated.
  uint16_t id = 0;
  Bytes payload;
  std::string error;
  EXPECT_TRUE(read_message(ByteVector{0x04, 0x00, 0x00, 0x00, 0x00}, id, payload, error)) << error;
  EXPECT_EQ(id, message::RequestModelDef);
  EXPECT_TRUE(payload.empty());
}

TEST(NatNet, ConnectMatchesFixture) {
  const ByteVector bytes = fixture("connect.bin");
  EXPECT_EQ(encode_connect("skinstream", k41), bytes);
  EXPECT_EQ(bytes[0], message::Connect);
  EXPECT_EQ(bytes[2] | bytes[3] << 8, 264);  // name[256] + version[4] + NatNet version[4]
}

TEST(NatNet, ServerInfoMatchesFixturesAndReadsBack) {
  ServerInfo info;
  info.application_name = "skinstream-replay";
  info.application_version = {0, 1, 0, 0};
  EXPECT_EQ(encode_server_info(info), fixture("server_info_4_1.bin"));
  info.natnet_version = {3, 1, 0, 0};
  info.multicast = false;
  EXPECT_EQ(encode_server_info(info), fixture("server_info_3_1.bin"));

  ServerInfo read;
  std::string error;
  ASSERT_TRUE(decode_server_info(payload_of(fixture("server_info_4_1.bin"), message::ServerInfo), read, error))
      << error;
  EXPECT_EQ(read.application_name, "skinstream-replay");
  EXPECT_EQ(read.version().major, 4);
  EXPECT_EQ(read.version().minor, 1);
  EXPECT_EQ(read.data_port, 1511);
  EXPECT_TRUE(read.multicast);
  EXPECT_EQ(read.multicast_group, (std::array<uint8_t, 4>{239, 255, 42, 99}));
  EXPECT_EQ(read.clock_ticks_per_second, 1'000'000'000u);
}

TEST(NatNet, ModelDefinitionsMatchFixturesInBothLayouts) {
  ModelDefinitions defs;
  defs.marker_sets.push_back({"walker", {"LASI", "RASI"}});
  for (const auto& [name, version] : {std::pair{"model_def_3_1.bin", k31}, std::pair{"model_def_4_1.bin", k41}}) {
    EXPECT_EQ(encode_model_definitions(defs, version), fixture(name)) << name;
    ModelDefinitions read;
    std::string error;
    ASSERT_TRUE(decode_model_definitions(payload_of(fixture(name), message::ModelDef), version, read, error))
        << name << ": " << error;
    ASSERT_EQ(read.marker_sets.size(), 1u);
    EXPECT_EQ(read.marker_sets[0].name, "walker");
    EXPECT_EQ(read.marker_sets[0].markers, (std::vector<std::string>{"LASI", "RASI"}));
  }
}

TEST(NatNet, OtherDescriptionsAreSkipped) {
  for (const auto& [name, version, skipped] :
       {std::tuple{"model_def_rigid_body_3_1.bin", k31, 1u}, std::tuple{"model_def_rigid_body_4_1.bin", k41, 2u}}) {
    ModelDefinitions read;
    std::string error;
    ASSERT_TRUE(decode_model_definitions(payload_of(fixture(name), message::ModelDef), version, read, error))
        << name << ": " << error;
    EXPECT_EQ(read.skipped_descriptions, skipped) << name;
    ASSERT_EQ(read.marker_sets.size(), 1u) << name;
    EXPECT_EQ(read.marker_sets[0].markers[1], "RASI");
  }
}

TEST(NatNet, FramesMatchFixturesInEachLayout) {
  const Capture capture = walker_capture();
  CaptureEncoder encoder({{"walker", &capture}});
  for (const auto& [name, version] :
       {std::pair{"frame_3_1.bin", k31}, std::pair{"frame_4_0.bin", k40}, std::pair{"frame_4_1.bin", k41}}) {
    ByteVector written;
    encoder.encode(1, version, written);
    EXPECT_EQ(written, fixture(name)) << name;

    const FrameOfData f = decoded_frame(fixture(name), version);
    EXPECT_EQ(f.frame_number, 11);
    ASSERT_EQ(f.marker_set_count, 1u);
    EXPECT_EQ(f.marker_sets[0].name, "walker");
    ASSERT_EQ(f.marker_sets[0].positions.size(), 2u);
    EXPECT_EQ(f.marker_sets[0].positions[0], (Point{0.1005f, -0.20025f, 0.950125f}));
    EXPECT_TRUE(std::isnan(f.marker_sets[0].positions[1][0]));
    ASSERT_EQ(f.other_markers.size(), 1u);
    ASSERT_EQ(f.labelled_markers.size(), 2u);
    EXPECT_EQ(f.labelled_markers[0].model_id(), 1);
    EXPECT_EQ(f.labelled_markers[0].member_id(), 1);
    EXPECT_EQ(f.labelled_markers[1].model_id(), 0);
    EXPECT_EQ(f.labelled_markers[1].member_id(), 7);
    EXPECT_EQ(f.labelled_markers[1].params, kMarkerUnlabelled);
    const TimecodeFields tc = split_timecode(f.timecode);
    EXPECT_EQ(tc.frames, 2);
    EXPECT_EQ(f.timecode_subframe, 1u);
    EXPECT_DOUBLE_EQ(f.timestamp_s, 1.0 / 120.0);
    EXPECT_EQ(f.stamp_transmit, 8'333'333u);
  }
}

TEST(NatNet, RigidBodiesSkeletonsAndAssetsAreSkipped) {
  const FrameOfData a = decoded_frame(fixture("frame_rigid_body_3_1.bin"), k31);
  EXPECT_EQ(a.rigid_bodies, 1u);
  EXPECT_EQ(a.skeletons, 1u);
  EXPECT_EQ(a.labelled_markers.size(), 2u);
  const FrameOfData b = decoded_frame(fixture("frame_asset_4_1.bin"), k41);
  EXPECT_EQ(b.assets, 1u);
  EXPECT_EQ(b.labelled_markers.size(), 2u);
  EXPECT_DOUBLE_EQ(b.timestamp_s, 1.0 / 120.0);
}

TEST(NatNet, WrongLayoutOrOldVersionIsRefused) {
  EXPECT_FALSE(error_of(fixture("frame_4_1.bin"), k31).empty());  // 4.1 bytes read as 3.1
  EXPECT_FALSE(error_of(fixture("frame_3_1.bin"), k41).empty());
  EXPECT_NE(error_of(fixture("frame_3_1.bin"), Version{2, 9}).find("not supported"), std::string::npos);
}

TEST(NatNet, EveryTruncationIsRejected) {
  for (const auto& [name, version] :
       {std::pair{"frame_3_1.bin", k31}, std::pair{"frame_4_1.bin", k41}, std::pair{"model_def_4_1.bin", k41},
        std::pair{"model_def_rigid_body_3_1.bin", k31}, std::pair{"server_info_4_1.bin", k41}}) {
    const ByteVector whole = fixture(name);
    for (size_t n = 0; n < whole.size(); ++n) {
      ByteVector cut(whole.begin(), whole.begin() + static_cast<long>(n));
      if (n >= 4) {  // keep the header consistent, so the payload itself is what is short
        const auto bytes = static_cast<uint16_t>(n - 4);
        std::memcpy(cut.data() + 2, &bytes, 2);
      }
      const bool frame = std::string(name).rfind("frame", 0) == 0, info = std::string(name).rfind("server", 0) == 0;
      if ((frame && n + 4 == whole.size()) || (info && n == 4 + 264))
        continue;  // whole: a frame without its optional end-of-data tag, server info before NatNet 3.0
      EXPECT_FALSE(error_of(cut, version).empty()) << name << " cut at " << n;
    }
  }
}

TEST(NatNet, InconsistentCountsAreRejected) {
  ByteVector count = fixture("frame_3_1.bin");
  put_i32(count, 8, 1000);  // marker set count far past the payload
  EXPECT_NE(error_of(count, k31).find("exceeds"), std::string::npos);
  ByteVector negative = fixture("frame_3_1.bin");
  put_i32(negative, 8, -1);
  EXPECT_NE(error_of(negative, k31).find("negative"), std::string::npos);
  ByteVector section = fixture("frame_4_1.bin");
  put_i32(section, 12, 20);  // the marker set section says 20 bytes; it holds 35
  EXPECT_NE(error_of(section, k41).find("says 20 bytes but holds"), std::string::npos);
  ByteVector header = fixture("frame_3_1.bin");
  header[2] = 0xFF;  // byte count past the datagram
  EXPECT_NE(error_of(header, k31).find("follow"), std::string::npos);
  ByteVector no_nul = fixture("model_def_3_1.bin");
  no_nul.resize(no_nul.size() - 1);  // the last marker name loses its NUL
  no_nul[2] = static_cast<unsigned char>(no_nul.size() - 4);
  EXPECT_NE(error_of(no_nul, k31).find("NUL"), std::string::npos);
  ByteVector trailing = fixture("frame_3_1.bin");
  trailing.insert(trailing.end(), {1, 2, 3});
  trailing[2] = static_cast<unsigned char>(trailing.size() - 4);
  EXPECT_NE(error_of(trailing, k31).find("after its end of data"), std::string::npos);
  EXPECT_NE(error_of(ByteVector{0x63, 0x00, 0x00, 0x00}, k41).find("unknown"), std::string::npos);
}

TEST(NatNet, EncoderSplitsSeveralRecordingsIntoMarkerSets) {
  const Capture a = walker_capture();
  Capture b({"X", "*3"}, 3, 120.0);
  for (int i = 0; i < 3; ++i) b.at(i, 0) = b.at(i, 1) = Vec3(1000.0 * i, 0, 0);
  CaptureEncoder encoder({{"walker", &a}, {"runner", &b}});
  ASSERT_EQ(encoder.model_definitions().marker_sets.size(), 2u);
  EXPECT_EQ(encoder.model_definitions().marker_sets[1].markers, std::vector<std::string>{"X"});
  ByteVector bytes;
  encoder.encode(2, k41, bytes);
  const FrameOfData f = decoded_frame(bytes, k41);
  ASSERT_EQ(f.marker_set_count, 2u);
  EXPECT_TRUE(std::isnan(f.marker_sets[0].positions[0][0]));  // walker has ended
  EXPECT_EQ(f.marker_sets[1].positions[0], (Point{2.0f, 0.0f, 0.0f}));  // 2000 mm in metres
  ASSERT_EQ(f.labelled_markers.size(), 2u);
  EXPECT_EQ(f.labelled_markers[0].model_id(), 2);
  EXPECT_EQ(f.labelled_markers[1].member_id(), 3 + CaptureEncoder::kUnlabelledIdStride);
}

TEST(NatNet, EncodingAndDecodingAFrameAllocateNothingOnceWarm) {
  const Capture capture = walker_capture();
  CaptureEncoder encoder({{"walker", &capture}});
  ByteVector bytes;
  FrameOfData frame;
  std::string error;
  encoder.encode(0, k41, bytes);
  ASSERT_TRUE(decode_frame(Bytes(bytes).subspan(4), k41, frame, error)) << error;
  test::CountAllocations counted;
  for (uint64_t k = 1; k < 50; ++k) {
    encoder.encode(k, k41, bytes);
    decode_frame(Bytes(bytes).subspan(4), k41, frame, error);
  }
  EXPECT_EQ(counted.count(), 0u);
}

TEST(NatNet, RandomCorruptionNeverCrashes) {
  std::mt19937 random(1511);
  int rejected = 0;
  for (const auto& [name, version] : {std::pair{"frame_rigid_body_3_1.bin", k31}, std::pair{"frame_asset_4_1.bin", k41},
                                      std::pair{"model_def_rigid_body_4_1.bin", k41}}) {
    const ByteVector good = fixture(name);
    for (int trial = 0; trial < 10000; ++trial) {
      ByteVector bytes = good;
      const int flips = 1 + static_cast<int>(random() % 4);
      for (int f = 0; f < flips; ++f) bytes[random() % bytes.size()] = static_cast<unsigned char>(random());
      Message m;
      std::string error;
      if (!decode_message(bytes, version, m, error)) ++rejected;
    }
  }
  EXPECT_GT(rejected, 1000);
}

}  // namespace
}  // namespace skinstream::natnet
