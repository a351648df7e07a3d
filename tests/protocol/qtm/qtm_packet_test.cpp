// QTM RT packets (protocol/qtm_packet_reader, _writer, _framer) against golden fixtures written
// independently of the writer (tests/protocol/fixtures/qtm/make_fixtures.py packs each packet
// with Python's struct from the protocol description), hand-spelled bytes, and bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

#include "protocol/qtm/qtm_packet_framer.h"
#include "protocol/qtm/qtm_packet_reader.h"
#include "protocol/qtm/qtm_packet_writer.h"
#include "support/fixture_bytes.h"

namespace skinstream::qtm {
namespace {

using test::ByteVector;
using test::bytes_of;

ByteVector fixture(const std::string& name) { return test::fixture_bytes("qtm/" + name); }

std::string text_of(const ByteVector& packet) {
  std::string text, error;
  EXPECT_TRUE(decode_text(packet, text, error)) << error;
  return text;
}

ByteVector data_3d_written() {
  const float nan = std::nanf("");
  const std::array<float, 3> labelled[] = {{100.5f, -200.25f, 950.125f}, {nan, nan, nan}};
  const UnlabelledMarker unlabelled[] = {{{1.f, 2.f, 3.f}, 7}};
  DataPacketWriter writer;
  writer.begin(8333, 11);
  writer.add_labelled(labelled);
  writer.add_unlabelled(unlabelled);
  return bytes_of(writer.finish());
}

std::string packet_error_of(const ByteVector& packet) {
  Packet out;
  std::string error;
  EXPECT_FALSE(decode_packet(packet, out, error)) << "accepted a bad packet";
  EXPECT_EQ(error.find('\n'), std::string::npos) << "error is not one line: " << error;
  return error;
}

void put_u32(ByteVector& bytes, size_t offset, uint32_t value) { std::memcpy(bytes.data() + offset, &value, 4); }

TEST(QtmPacket, WelcomeIsSpelledOutByHand) {
  ByteVector expected = {
      0x23, 0x00, 0x00, 0x00,  // u32 size 35: 8-byte header + 26 characters + NUL
      0x01, 0x00, 0x00, 0x00,  // u32 type Command
  };
  for (char c : std::string("QTM RT Interface connected")) expected.push_back(static_cast<unsigned char>(c));
  expected.push_back(0);
  EXPECT_EQ(encode_text(PacketType::Command, kWelcome), expected);
  EXPECT_EQ(fixture("welcome.bin"), expected);
  EXPECT_EQ(text_of(expected), kWelcome);
}

TEST(QtmPacket, TextPacketsMatchFixtures) {
  const std::pair<const char*, const char*> commands[] = {
      {"version_command.bin", "Version 1.19"},
      {"version_reply.bin", "Version set to 1.19"},
      {"get_parameters_command.bin", "GetParameters General 3D"},
      {"stream_frames_command.bin", "StreamFrames AllFrames 3D 3DNoLabels"},
  };
  for (const auto& [name, text] : commands) {
    EXPECT_EQ(encode_text(PacketType::Command, text), fixture(name)) << name;
    EXPECT_EQ(text_of(fixture(name)), text) << name;
  }
  EXPECT_EQ(encode_text(PacketType::Error, "Command not supported"), fixture("error.bin"));
  Packet error_packet;
  std::string error;
  ASSERT_TRUE(decode_packet(fixture("error.bin"), error_packet, error)) << error;
  EXPECT_EQ(error_packet.type, static_cast<uint32_t>(PacketType::Error));
  EXPECT_EQ(error_packet.text, "Command not supported");
}

TEST(QtmPacket, TextWithoutNulIsReadToTheEnd) {
  // Clients (qualisys-rt) send commands without the NUL QTM puts after its own.
  ByteVector packet = {20, 0, 0, 0, 1, 0, 0, 0};
  for (char c : std::string("GetState    ")) packet.push_back(static_cast<unsigned char>(c));
  EXPECT_EQ(text_of(packet), "GetState    ");
}

TEST(QtmPacket, EventAndNoMoreDataMatchFixtures) {
  EXPECT_EQ(encode_event(Event::RtFromFileStarted), fixture("event_rt_from_file_started.bin"));
  Event event = Event::Connected;
  std::string error;
  ASSERT_TRUE(decode_event(fixture("event_rt_from_file_started.bin"), event, error)) << error;
  EXPECT_EQ(event, Event::RtFromFileStarted);
  EXPECT_EQ(encode_no_more_data(), fixture("no_more_data.bin"));
  Packet packet;
  ASSERT_TRUE(decode_packet(fixture("no_more_data.bin"), packet, error)) << error;
  EXPECT_EQ(packet.type, static_cast<uint32_t>(PacketType::NoMoreData));
}

TEST(QtmPacket, DataPacketMatchesFixture) {
  const ByteVector bytes = fixture("data_3d.bin");
  EXPECT_EQ(data_3d_written(), bytes);
  DataFrame frame;
  std::string error;
  ASSERT_TRUE(decode_data(bytes, frame, error)) << error;
  EXPECT_EQ(frame.timestamp_us, 8333);
  EXPECT_EQ(frame.frame_number, 11u);
  ASSERT_TRUE(frame.has_labelled);
  ASSERT_EQ(frame.labelled.size(), 2u);
  EXPECT_EQ(frame.labelled[0], (std::array<float, 3>{100.5f, -200.25f, 950.125f}));
  EXPECT_TRUE(std::isnan(frame.labelled[1][0]) && std::isnan(frame.labelled[1][2]));
  ASSERT_TRUE(frame.has_unlabelled);
  ASSERT_EQ(frame.unlabelled.size(), 1u);
  EXPECT_EQ(frame.unlabelled[0].position, (std::array<float, 3>{1.f, 2.f, 3.f}));
  EXPECT_EQ(frame.unlabelled[0].id, 7u);
}

TEST(QtmPacket, ResidualComponentsAreRead) {
  DataFrame frame;
  std::string error;
  ASSERT_TRUE(decode_data(fixture("data_3d_residuals.bin"), frame, error)) << error;
  ASSERT_EQ(frame.labelled.size(), 2u);
  EXPECT_EQ(frame.labelled[0], (std::array<float, 3>{100.5f, -200.25f, 950.125f}));
  EXPECT_TRUE(std::isnan(frame.labelled[1][1]));
  ASSERT_EQ(frame.unlabelled.size(), 1u);
  EXPECT_EQ(frame.unlabelled[0].id, 7u);  // after the residual, not the residual
  EXPECT_EQ(frame.drop_rate_2d, 3);
  EXPECT_EQ(frame.out_of_sync_rate_2d, 4);
}

TEST(QtmPacket, OtherComponentsAreSkippedAndCounted) {
  ByteVector bytes = data_3d_written();
  // Append a 6D component (type 5) of 12 bytes and count it in the header.
  const unsigned char six_d[] = {12, 0, 0, 0, 5, 0, 0, 0, 0, 0, 0, 0};
  bytes.insert(bytes.end(), std::begin(six_d), std::end(six_d));
  put_u32(bytes, 0, static_cast<uint32_t>(bytes.size()));
  put_u32(bytes, 20, 3);
  DataFrame frame;
  std::string error;
  ASSERT_TRUE(decode_data(bytes, frame, error)) << error;
  EXPECT_EQ(frame.skipped_components, 1u);
  EXPECT_EQ(frame.labelled.size(), 2u);
}

TEST(QtmPacket, EveryTruncationIsRejected) {
  for (const char* name : {"welcome.bin", "data_3d.bin", "data_3d_residuals.bin", "event_rt_from_file_started.bin",
                           "parameters_xml.bin"}) {
    const ByteVector whole = fixture(name);
    for (size_t n = 0; n < whole.size(); ++n) {
      const ByteVector cut(whole.begin(), whole.begin() + static_cast<long>(n));
      EXPECT_FALSE(packet_error_of(cut).empty()) << name << " cut at " << n;
    }
  }
}

TEST(QtmPacket, InconsistentDataIsRejected) {
  const ByteVector good = fixture("data_3d.bin");
  ByteVector more_markers = good;
  put_u32(more_markers, 32, 3);  // the 3D component says 3 markers but holds 2
  EXPECT_NE(packet_error_of(more_markers).find("says 3 markers"), std::string::npos);

  ByteVector overrun = good;
  put_u32(overrun, 24, 1000);  // the first component runs past the packet
  EXPECT_NE(packet_error_of(overrun).find("1000 bytes"), std::string::npos);

  ByteVector extra_component = good;
  put_u32(extra_component, 20, 3);  // three components announced, two present
  EXPECT_NE(packet_error_of(extra_component).find("component 3 of 3"), std::string::npos);

  ByteVector trailing = good;
  trailing.push_back(0);
  put_u32(trailing, 0, static_cast<uint32_t>(trailing.size()));
  EXPECT_NE(packet_error_of(trailing).find("after its 2 components"), std::string::npos);

  ByteVector twice = good;  // the 3D no labels component turned into a second 3D one
  put_u32(twice, 68, component::k3d);
  EXPECT_FALSE(packet_error_of(twice).empty());

  ByteVector size_mismatch = good;
  put_u32(size_mismatch, 0, static_cast<uint32_t>(good.size() + 4));
  EXPECT_NE(packet_error_of(size_mismatch).find("size field"), std::string::npos);

  ByteVector oversize = good;
  put_u32(oversize, 0, kMaxPacketBytes + 1);
  EXPECT_NE(packet_error_of(oversize).find("limit"), std::string::npos);

  ByteVector long_event = fixture("event_rt_from_file_started.bin");
  long_event.push_back(0);
  put_u32(long_event, 0, 10);
  EXPECT_FALSE(packet_error_of(long_event).empty());

  EXPECT_NE(packet_error_of({8, 0, 0, 0, 99, 0, 0, 0}).find("unsupported packet type 99"), std::string::npos);
}

TEST(QtmPacket, FramerCutsAStreamFedByteByByte) {
  ByteVector stream = fixture("welcome.bin");
  for (const char* name : {"data_3d.bin", "no_more_data.bin", "parameters_xml.bin"}) {
    const ByteVector b = fixture(name);
    stream.insert(stream.end(), b.begin(), b.end());
  }
  PacketFramer framer;
  std::vector<ByteVector> packets;
  for (unsigned char byte : stream) {
    framer.feed(Bytes(&byte, 1));
    Bytes packet;
    while (framer.next(packet) == PacketFramer::Status::Packet) packets.push_back(bytes_of(packet));
  }
  ASSERT_EQ(packets.size(), 4u);
  EXPECT_EQ(packets[1], fixture("data_3d.bin"));
  EXPECT_EQ(packets[3], fixture("parameters_xml.bin"));
  EXPECT_EQ(framer.buffered(), 0u);
}

TEST(QtmPacket, FramerRejectsImpossibleSizesFromTheHeaderAlone) {
  for (uint32_t size : {0u, 7u, kMaxPacketBytes + 1}) {
    PacketFramer framer;
    ByteVector header(8, 0);
    put_u32(header, 0, size);
    framer.feed(header);
    Bytes packet;
    EXPECT_EQ(framer.next(packet), PacketFramer::Status::Error) << size;
    EXPECT_FALSE(framer.error().empty());
    framer.reset();
    EXPECT_EQ(framer.next(packet), PacketFramer::Status::NeedMore);
  }
}

TEST(QtmPacket, RandomCorruptionNeverCrashes) {
  std::mt19937 random(36);
  const ByteVector good = fixture("data_3d_residuals.bin");
  int rejected = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    ByteVector bytes = good;
    const int flips = 1 + static_cast<int>(random() % 4);
    for (int f = 0; f < flips; ++f) bytes[random() % bytes.size()] = static_cast<unsigned char>(random());
    Packet packet;
    std::string error;
    if (!decode_packet(bytes, packet, error)) ++rejected;
  }
  EXPECT_GT(rejected, 1000);  // most damage to sizes and counts is caught
}

}  // namespace
}  // namespace skinstream::qtm
