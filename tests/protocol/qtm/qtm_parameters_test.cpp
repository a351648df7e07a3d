// The 3D parameters XML (protocol/qtm_parameters): written as the fixture spells it, read back by
// expat, and refused when malformed or inconsistent.
#include <gtest/gtest.h>

#include "protocol/qtm/qtm_packet_reader.h"
#include "protocol/qtm/qtm_parameters.h"
#include "support/fixture_bytes.h"
#include "support/test_data.h"

namespace skinstream::qtm {
namespace {

Parameters walker() {
  Parameters p;
  p.frequency_hz = 120;
  p.capture_time_s = 2.5;
  p.has_3d = true;
  p.labels = {"walker_LASI", "walker_R&ASI"};
  return p;
}

std::string fixture_xml() {
  std::string text, error;
  EXPECT_TRUE(decode_text(test::fixture_bytes("qtm/parameters_xml.bin"), text, error)) << error;
  return text;
}

std::string parse_error(const std::string& xml) {
  Parameters p;
  std::string error;
  EXPECT_FALSE(parse_parameters_xml(xml, p, error)) << "accepted: " << xml;
  EXPECT_EQ(error.find('\n'), std::string::npos) << error;
  return error;
}

TEST(QtmParameters, WrittenAsTheFixture) { EXPECT_EQ(write_parameters_xml(walker(), 19), fixture_xml()); }

TEST(QtmParameters, FixtureReadsBack) {
  Parameters p;
  std::string error;
  ASSERT_TRUE(parse_parameters_xml(fixture_xml(), p, error)) << error;
  EXPECT_TRUE(p.has_3d);
  EXPECT_DOUBLE_EQ(p.frequency_hz, 120.0);
  EXPECT_DOUBLE_EQ(p.capture_time_s, 2.5);
  EXPECT_EQ(p.axis_upwards, "+Z");
  EXPECT_EQ(p.labels, (std::vector<std::string>{"walker_LASI", "walker_R&ASI"}));  // &amp; decoded
}

TEST(QtmParameters, QtmsOwnLayoutWithBonesAndDeclarationIsRead) {
  // As QTM sends it (the layout of the Qualisys SDK's test data): a declaration, trajectory types,
  // bones after the labels, attributes; labels are taken from The_3D only.
  const std::string xml =
      "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<QTM_Parameters_Ver_1.25><The_3D><AxisUpwards>+Y</AxisUpwards>"
      "<CalibrationTime>2019-09-17 16:00:43</CalibrationTime><Labels>2</Labels>"
      "<Label><Name>VF_HeadL</Name><RGBColor>16763904</RGBColor><Trajectory_Type>Measured</Trajectory_Type></Label>"
      "<Label><Name>Screen - 4</Name><RGBColor>127</RGBColor></Label>"
      "<Bones><Bone From=\"VF_HeadL\" To=\"Screen - 4\" Color=\"1\"/></Bones></The_3D>"
      "<The_6D><Bodies>1</Bodies><Body><Name>NotALabel</Name></Body></The_6D></QTM_Parameters_Ver_1.25>";
  Parameters p;
  std::string error;
  ASSERT_TRUE(parse_parameters_xml(xml, p, error)) << error;
  EXPECT_EQ(p.labels, (std::vector<std::string>{"VF_HeadL", "Screen - 4"}));
  EXPECT_EQ(p.axis_upwards, "+Y");
  EXPECT_DOUBLE_EQ(p.frequency_hz, 0.0);
}

TEST(QtmParameters, NoThe3DMeansNoLabels) {
  Parameters p;
  std::string error;
  ASSERT_TRUE(parse_parameters_xml("<QTM_Parameters_Ver_1.19><General><Frequency>100</Frequency></General>"
                                   "</QTM_Parameters_Ver_1.19>",
                                   p, error))
      << error;
  EXPECT_FALSE(p.has_3d);
  EXPECT_DOUBLE_EQ(p.frequency_hz, 100.0);
}

TEST(QtmParameters, MalformedOrInconsistentIsRefused) {
  EXPECT_NE(parse_error("<QTM_Parameters_Ver_1.19><The_3D>").find("line"), std::string::npos);
  EXPECT_FALSE(parse_error("").empty());
  EXPECT_FALSE(parse_error("<a></b>").empty());
  EXPECT_NE(parse_error("<R><The_3D><Labels>3</Labels><Label><Name>A</Name></Label></The_3D></R>")
                .find("says 3 labels but names 1"),
            std::string::npos);
  EXPECT_FALSE(parse_error("<R><The_3D><Labels>two</Labels></The_3D></R>").empty());
  EXPECT_FALSE(parse_error("<R><General><Frequency>nan</Frequency></General></R>").empty());
  EXPECT_NE(parse_error("<R><The_3D><Label><Name>" + std::string(2000, 'x') + "</Name></Label></The_3D></R>")
                .find("longer than 1024"),
            std::string::npos);
  // Entity expansion (10^9 "a"s from a few hundred bytes) is stopped by expat, not performed.
  std::string bomb = "<?xml version=\"1.0\"?><!DOCTYPE R [<!ENTITY e0 \"aaaaaaaaaa\">";
  for (int i = 1; i < 10; ++i) {
    bomb += "<!ENTITY e" + std::to_string(i) + " \"";
    for (int k = 0; k < 10; ++k) bomb += "&e" + std::to_string(i - 1) + ";";
    bomb += "\">";
  }
  bomb += "]><R><The_3D><AxisUpwards>&e9;</AxisUpwards></The_3D></R>";
  EXPECT_FALSE(parse_error(bomb).empty());
}

// Found by fuzzing (tests/fuzz/qtm_parameters_fuzz.cpp): a Labels count that is not one was
// quoted into the error with its line break. The error is now one printable line.
TEST(QtmParameters, TextQuotedInAnErrorIsMadePrintable) {
  const std::string xml = test::read_bytes(test::source_path("tests/protocol/fixtures/fuzz/qtm_parameters_labels_line_break.xml"));
  EXPECT_EQ(parse_error(xml), "The_3D/Labels is not a count: '1meters_Ver_1.19>\\x0a'");
  EXPECT_EQ(parse_error("<R><General><Frequency>fast&#9;</Frequency></General></R>"),
            "General/Frequency is not a frequency: 'fast\\x09'");
}

// Found by fuzzing (tests/fuzz/qtm_parameters_fuzz.cpp): a Labels count of 129 digits was
// converted to a long (undefined behaviour, reported by UBSan, before expat found the
// document malformed further on). A count over the parser's limit
// of labels is refused before it is converted.
TEST(QtmParameters, ALabelsCountBeyondTheLimitIsRefused) {
  const std::string xml = test::read_bytes(test::source_path("tests/protocol/fixtures/fuzz/qtm_parameters_labels_count_overflow.xml"));
  EXPECT_FALSE(parse_error(xml).empty());  // the document is not well-formed further on, which expat says
  EXPECT_EQ(parse_error("<R><The_3D><Labels>1" + std::string(128, '5') + "</Labels></The_3D></R>"),
            "The_3D/Labels says '1555555555555555555555555555555555555555... (129 bytes)', more than 100000 labels");
  EXPECT_NE(parse_error("<R><The_3D><Labels>100001</Labels></The_3D></R>").find("more than 100000 labels"), std::string::npos);
  EXPECT_NE(parse_error("<R><The_3D><Labels>100000</Labels></The_3D></R>").find("says 100000 labels but names 0"), std::string::npos);
}

}  // namespace
}  // namespace skinstream::qtm
