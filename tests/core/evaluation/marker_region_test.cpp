#include "core/evaluation/marker_region.h"

#include <gtest/gtest.h>

#include <algorithm>

namespace skinstream {
namespace {

TEST(MarkerRegion, EmptyAndUnknownNamesAreOther) {
  EXPECT_EQ(marker_region(""), "other");
  EXPECT_EQ(marker_region("*12"), "other");
  EXPECT_EQ(marker_region("Sync:Sync"), "other");
  EXPECT_EQ(marker_region("L"), "other");
  EXPECT_EQ(marker_region("limb_0_3"), "other");
  EXPECT_EQ(marker_region("elbow_x"), "other");
  EXPECT_EQ(marker_region("WheelchairL:Marker1"), "other");
}

TEST(MarkerRegion, CoversTheCmuMarkerSet) {
  // Labels as stored in CMU 85_02.c3d / 85_12.c3d, subject prefix included.
  const std::vector<std::pair<std::string, std::string>> expected = {
      {"Male:LFWT", "pelvis"},   {"Male:RFWT", "pelvis"},    {"Male:LBWT", "pelvis"},
      {"Male:RBWT", "pelvis"},   {"Male:LTHI", "thigh"},     {"Male:LKNE", "knee"},
      {"Male:LSHN", "shank"},    {"Male:LANK", "foot"},      {"Male:LHEE", "foot"},
      {"Male:LMT5", "foot"},     {"Male:LTOE", "foot"},      {"Male:RTHI", "thigh"},
      {"Male:RKNE", "knee"},     {"Male:RSHN", "shank"},     {"Male:RANK", "foot"},
      {"Male:RHEE", "foot"},     {"Male:RMT5", "foot"},      {"Male:RTOE", "foot"},
      {"Male:CLAV", "torso"},    {"Male:STRN", "torso"},     {"Male:C7", "torso"},
      {"Male:T10", "torso"},     {"Male:RBAC", "torso"},     {"Male:LFHD", "head"},
      {"Male:RFHD", "head"},     {"Male:LBHD", "head"},      {"Male:RBHD", "head"},
      {"Male:LSHO", "shoulder"}, {"Male:LUPA", "upper_arm"}, {"Male:LELB", "elbow"},
      {"Male:LFRM", "forearm"},  {"Male:LWRA", "hand"},      {"Male:LWRB", "hand"},
      {"Male:LFIN", "hand"},     {"Male:RSHO", "shoulder"},  {"Male:RUPA", "upper_arm"},
      {"Male:RELB", "elbow"},    {"Male:RFRM", "forearm"},   {"Male:RWRA", "hand"},
      {"Male:RWRB", "hand"},     {"Male:RFIN", "hand"}};
  for (const auto& [label, region] : expected) EXPECT_EQ(marker_region(label), region) << label;
}

TEST(MarkerRegion, HandlesHdm05AndOtherPlugInGaitVariants) {
  EXPECT_EQ(marker_region("Bastian:LFHD"), "head");
  EXPECT_EQ(marker_region("Bastian:RMT5"), "foot");
  EXPECT_EQ(marker_region("Derrick:LASI"), "pelvis");
  EXPECT_EQ(marker_region("Derrick:RPSI"), "pelvis");
  EXPECT_EQ(marker_region("Derrick:LTIB"), "shank");
  EXPECT_EQ(marker_region("Derrick:RBAK"), "torso");
  EXPECT_EQ(marker_region("SACR"), "pelvis");
  EXPECT_EQ(marker_region("LWRI"), "hand");
  EXPECT_EQ(marker_region("lelb"), "elbow");  // case-insensitive
}

TEST(MarkerRegion, HandlesGridNames) {
  EXPECT_EQ(marker_region("abdomen_12"), "torso");
  EXPECT_EQ(marker_region("elbow_3"), "elbow");
  EXPECT_EQ(marker_region("upper_arm_7"), "upper_arm");
  EXPECT_EQ(marker_region("thigh_2_5"), "thigh");
  EXPECT_EQ(marker_region("l_knee_4"), "knee");
  EXPECT_EQ(marker_region("Right_Shin_9"), "shank");
  EXPECT_EQ(marker_region("Subject:forearm_0"), "forearm");
  EXPECT_EQ(marker_region("chest"), "torso");
  EXPECT_EQ(marker_region("wrist_1"), "hand");
}

TEST(MarkerRegion, EveryResultIsAListedRegion) {
  const std::vector<std::string>& regions = marker_regions();
  EXPECT_EQ(regions.back(), "other");
  for (const char* label : {"LFHD", "C7", "LSHO", "LUPA", "LELB", "LFRM", "LFIN", "LFWT", "LTHI", "LKNE",
                            "LSHN", "LANK", "abdomen_1", "nothing"})
    EXPECT_NE(std::find(regions.begin(), regions.end(), marker_region(label)), regions.end()) << label;
}

}  // namespace
}  // namespace skinstream
