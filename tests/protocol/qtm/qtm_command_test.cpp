// QTM RT commands (protocol/qtm_command) and the actor prefixes of labels (protocol/qtm_labels).
#include <gtest/gtest.h>

#include <algorithm>

#include "protocol/qtm/qtm_command.h"
#include "protocol/qtm/qtm_labels.h"
#include "protocol/qtm/qtm_packet_reader.h"
#include "support/test_data.h"

namespace skinstream::qtm {
namespace {

Command parsed(const std::string& text) {
  Command c;
  std::string error;
  EXPECT_TRUE(parse_command(text, c, error)) << text << ": " << error;
  return c;
}

std::string command_error_of(const std::string& text) {
  Command c;
  std::string error;
  EXPECT_FALSE(parse_command(text, c, error)) << "accepted: " << text;
  return error;
}

TEST(QtmCommand, Version) {
  const Command c = parsed("Version 1.19");
  EXPECT_EQ(c.kind, Command::Kind::Version);
  EXPECT_EQ(c.major, 1);
  EXPECT_EQ(c.minor, 19);
  EXPECT_EQ(parsed("version").minor, -1);  // asks for the version in use
  EXPECT_FALSE(command_error_of("Version one.two").empty());
  EXPECT_FALSE(command_error_of("Version 1.").empty());
}

TEST(QtmCommand, StreamFramesWithRateUdpAndComponents) {
  Command c = parsed("StreamFrames AllFrames 3D 3DNoLabels");
  EXPECT_EQ(c.kind, Command::Kind::StreamFrames);
  EXPECT_EQ(c.rate, Command::Rate::AllFrames);
  EXPECT_EQ(c.components, (std::vector<std::string>{"3D", "3DNoLabels"}));
  EXPECT_FALSE(c.udp);

  c = parsed("streamframes Frequency:60 UDP:127.0.0.1:5000 3d");
  EXPECT_EQ(c.rate, Command::Rate::Frequency);
  EXPECT_EQ(c.rate_value, 60u);
  EXPECT_TRUE(c.udp);
  EXPECT_EQ(c.udp_address, "127.0.0.1");
  EXPECT_EQ(c.udp_port, 5000);
  EXPECT_EQ(c.components, std::vector<std::string>{"3d"});

  c = parsed("StreamFrames FrequencyDivisor:2 UDP:6000 3D");
  EXPECT_EQ(c.rate, Command::Rate::FrequencyDivisor);
  EXPECT_EQ(c.udp_port, 6000);
  EXPECT_TRUE(c.udp_address.empty());

  EXPECT_EQ(parsed("StreamFrames Stop").kind, Command::Kind::StreamFramesStop);
  EXPECT_FALSE(command_error_of("StreamFrames Frequency:0 3D").empty());
  EXPECT_FALSE(command_error_of("StreamFrames AllFrames").empty());
  EXPECT_FALSE(command_error_of("StreamFrames AllFrames UDP:70000 3D").empty());
  EXPECT_FALSE(command_error_of("StreamFrames").empty());
}

TEST(QtmCommand, OthersAndUnknown) {
  EXPECT_EQ(parsed("GetState").kind, Command::Kind::GetState);
  const Command p = parsed("GetParameters General 3D");
  EXPECT_EQ(p.kind, Command::Kind::GetParameters);
  EXPECT_EQ(p.components, (std::vector<std::string>{"General", "3D"}));
  EXPECT_EQ(parsed("TakeControl secret").kind, Command::Kind::Other);
  EXPECT_EQ(parsed("TakeControl secret").word, "TakeControl");
  EXPECT_FALSE(command_error_of("   ").empty());
}

TEST(QtmCommand, StreamFramesCommandIsWrittenAsParsed) {
  EXPECT_EQ(stream_frames_command({"3D", "3DNoLabels"}), "StreamFrames AllFrames 3D 3DNoLabels");
  const Command c = parsed(stream_frames_command({"3D"}, 7000));
  EXPECT_EQ(c.udp_port, 7000);
  EXPECT_EQ(c.components, std::vector<std::string>{"3D"});
}

TEST(QtmLabels, PrefixesSplitAtTheFirstUnderscore) {
  EXPECT_EQ(prefixed_label("Actor1", "LFHD"), "Actor1_LFHD");
  EXPECT_EQ(prefixed_label("85_02", "LFHD"), "85-02_LFHD");
  EXPECT_EQ(prefixed_label("", "LFHD"), "LFHD");
  const SplitLabel a = split_label("85-02_L_FHD");
  EXPECT_EQ(a.subject, "85-02");
  EXPECT_EQ(a.marker, "L_FHD");
  const SplitLabel b = split_label("LFHD");
  EXPECT_EQ(b.subject, "");
  EXPECT_EQ(b.marker, "LFHD");
  EXPECT_EQ(split_label("_X").marker, "_X");
}

// Found by fuzzing (tests/fuzz/qtm_command_fuzz.cpp and qtm_packets_fuzz.cpp): a bad rate or
// version was quoted into the error as it came, control bytes and all. The error is now one
// printable line, the peer's bytes escaped.
TEST(QtmCommand, ControlBytesInARefusedCommandAreEscapedInTheError) {
  const auto printable = [](const std::string& text) {
    return std::all_of(text.begin(), text.end(), [](char c) { return c >= 0x20 && c < 0x7f; });
  };
  const std::string stream_frames = test::read_bytes(test::source_path("tests/protocol/fixtures/fuzz/qtm_command_control_bytes.txt"));
  const std::string rate_error = command_error_of(stream_frames);
  EXPECT_TRUE(printable(rate_error)) << rate_error;
  EXPECT_EQ(rate_error, "StreamFrames: bad rate 'AllFra\\x89es'");

  const std::string packet = test::read_bytes(test::source_path("tests/protocol/fixtures/fuzz/qtm_version_command_control_bytes.bin"));
  Packet decoded;
  std::string error;
  ASSERT_TRUE(decode_packet({reinterpret_cast<const unsigned char*>(packet.data()), packet.size()}, decoded, error)) << error;
  const std::string version_error = command_error_of(decoded.text);
  EXPECT_TRUE(printable(version_error)) << version_error;
  EXPECT_EQ(version_error.rfind("Version: bad version 'Version 1.1\\xba", 0), 0u) << version_error;
}

}  // namespace
}  // namespace skinstream::qtm
