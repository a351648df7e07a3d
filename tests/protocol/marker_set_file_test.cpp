// Marker-set files: malformed files refused with one line each, every field read.
#include "protocol/marker_set_file.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "protocol/file_error.h"
#include "support/file_error_assertion.h"
#include "support/test_data.h"

namespace skinstream {
namespace {

std::string write_set(const std::string& name, const std::string& text) {
  const std::string path = test::scratch_path(name);
  test::write_bytes(path, text);
  return path;
}

// A valid file, then the same with one thing broken: each refusal is one line naming the file,
// the entry and what is wrong.
const char* kGood = R"({"name": "Test set", "source": "this test",
  "markers": [
    {"name": "LELB", "aliases": ["LEL"], "description": "left elbow", "bone": "lowerarm01.L", "along": 0.0,
     "direction": [-2, 0, 0], "radius_mm": 25},
    {"name": "C7", "bone": "neck01", "direction": [0, -1, 0.2]},
    {"pattern": "thigh_L_*", "bones": ["upperleg*.L"], "side": "front"}
  ]})";

std::string broken(const std::string& from, const std::string& to) {
  std::string text = kGood;
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return text.replace(at, from.size(), to);
}

TEST(MarkerSetFile, RefusesMalformedFilesWithOneLineEach) {
  struct Case {
    std::string text, fragment;
  };
  const std::string e1 = "marker set 'Test set' entry 1 (LELB): ",
                    e3 = "marker set 'Test set' entry 3 (thigh_L_*): ";
  const std::vector<Case> cases = {
      {"", "not valid JSON"},
      {"{\"name\": \"x\",", "not valid JSON"},
      {"[1, 2]", "the marker set: must be a JSON object"},
      {broken("\"source\": \"this test\",", ""), "the marker set: has no \"source\""},
      {broken("\"name\": \"Test set\"", "\"name\": 7"), "the marker set: \"name\" must be a string"},
      {broken("\"source\": \"this test\",", "\"source\": \"a\", \"source\": \"b\","),
       "key 'source' appears twice in one object"},
      {broken("\"source\": \"this test\",", "\"source\": \"a\", \"author\": \"b\","),
       "the marker set: unknown key 'author'"},
      {broken("\"source\": \"this test\",", "\"source\": \"a\", \"notes\": [1],"),
       "the marker set: \"notes\" must be a string"},
      {broken("\"markers\": [", "\"markers\": {\"a\": ["), "not valid JSON"},
      {R"({"name": "n", "source": "s", "markers": {}})", "the marker set: \"markers\" must be an array"},
      {R"({"name": "n", "source": "s", "markers": []})", "marker set 'n': has no markers"},
      {R"({"name": "n", "source": "s", "markers": [3]})", "marker set 'n' entry 1: must be a JSON object"},
      {broken("\"name\": \"C7\", ", ""),
       "marker set 'Test set' entry 2: needs either \"name\" (one marker) or \"pattern\" (a region)"},
      {broken("\"pattern\": \"thigh_L_*\",", "\"pattern\": \"thigh_L_*\", \"name\": \"T\","),
       "needs either \"name\""},
      {broken("\"aliases\": [\"LEL\"]", "\"aliases\": \"LEL\""),
       e1 + "\"aliases\" must be an array of strings"},
      {broken("\"aliases\": [\"LEL\"]", "\"aliases\": [\"LEL\", 4]"),
       e1 + "\"aliases\" must be an array of strings"},
      {broken("\"along\": 0.0", "\"along\": \"0\""), e1 + "\"along\" must be a finite number"},
      {broken("\"along\": 0.0", "\"along\": 1e400"),
       "not valid JSON: [json.exception.out_of_range.406] number overflow"},
      {broken("\"along\": 0.0", "\"along\": 1.5"), e1 + "along must be in [0, 1]"},
      {broken("[-2, 0, 0]", "[-2, 0]"), e1 + "\"direction\" must be 3 finite numbers"},
      {broken("[-2, 0, 0]", "[-2, \"0\", 0]"), e1 + "\"direction\" must be 3 finite numbers"},
      {broken("[-2, 0, 0]", "[0, 0, 0]"), e1 + "\"direction\" must not be zero"},
      {broken("\"direction\": [-2, 0, 0], ", ""), e1 + "has no \"direction\""},
      {broken("\"radius_mm\": 25", "\"radius_mm\": 0"), e1 + "radius_mm must be in (0, 500]"},
      {broken("\"radius_mm\": 25", "\"radius_mm\": 501"), e1 + "radius_mm must be in (0, 500]"},
      {broken("\"radius_mm\": 25", "\"radius_mm\": 25, \"diretion\": [1, 0, 0]"),
       e1 + "unknown key 'diretion'"},
      {broken("\"bone\": \"lowerarm01.L\", ", ""), e1 + "has no \"bone\""},
      {broken("\"name\": \"LELB\"", "\"name\": \"L ELB\""), "entry 1 (L ELB): name holds a space"},
      {broken("\"name\": \"LELB\"", "\"name\": \"Sub:LELB\""), "entry 1 (Sub:LELB): name holds ':'"},
      {broken("\"name\": \"C7\"", "\"name\": \"lelb\""),
       "entry 2 (lelb): name 'lelb' repeats one of marker set 'Test set' entry 1 (LELB)"},
      {broken("\"name\": \"C7\"", "\"name\": \"thigh_L_9\""),
       "name 'thigh_L_9' is also matched by the pattern of"},
      {broken("\"thigh_L_*\"", "\"thigh_L\""), "entry 3 (thigh_L): pattern has no '*'"},
      {broken("\"bones\": [\"upperleg*.L\"]", "\"bones\": []"), e3 + "has no bones"},
      {broken("\"bones\": [\"upperleg*.L\"]", "\"bone\": \"upperleg01.L\""), e3 + "has no \"bones\""},
      {broken("\"side\": \"front\"", "\"side\": \"left\""),
       e3 + "\"side\" must be \"front\", \"back\" or \"any\", not 'left'"},
      {broken("\"side\": \"front\"", "\"side\": \"front\", \"radius_mm\": 20"),
       e3 + "unknown key 'radius_mm'"},
      {broken("\"description\": \"left elbow\"", "\"description\": \"left\\nelbow\""),
       e1 + "description holds a control character"},
  };
  ASSERT_NO_THROW(read_marker_set(write_set("good.json", kGood)));
  for (size_t i = 0; i < cases.size(); ++i) {
    const std::string path = write_set("bad" + std::to_string(i) + ".json", cases[i].text);
    EXPECT_TRUE(test::throws_file_error([&] { read_marker_set(path); }, path, cases[i].fragment))
        << "case " << i;
  }
  // A name with a terminal escape is quoted printably: the message stays one line.
  const std::string escaped =
      write_set("escape.json", broken("\"name\": \"LELB\"", "\"name\": \"L\\u001b[2J\""));
  EXPECT_TRUE(test::throws_file_error([&] { read_marker_set(escaped); }, escaped, "not printable ASCII"));
}

TEST(MarkerSetFile, RefusesMissingFilesAndBadFolders) {
  const std::string missing = test::scratch_path("no_such_set.json");
  EXPECT_TRUE(test::throws_file_error([&] { read_marker_set(missing); }, missing, "cannot open"));
  const std::string no_folder = test::scratch_path("no_such_folder");
  EXPECT_TRUE(
      test::throws_file_error([&] { read_marker_sets(no_folder); }, no_folder, "cannot read the folder"));
  const std::string empty = test::scratch_path("empty_sets");
  std::filesystem::create_directories(empty);
  test::write_bytes(empty + "/readme.txt", "not a set");
  EXPECT_TRUE(
      test::throws_file_error([&] { read_marker_sets(empty); }, empty, "holds no marker set (*.json)"));
  const std::string twice = test::scratch_path("twice_sets");
  std::filesystem::create_directories(twice);
  test::write_bytes(twice + "/a.json", kGood);
  test::write_bytes(twice + "/b.json", broken("\"Test set\"", "\"TEST SET\""));
  EXPECT_TRUE(test::throws_file_error([&] { read_marker_sets(twice); }, twice + "/b.json",
                                      "marker set 'TEST SET' is also defined in " + twice + "/a.json"));
  const std::string bad_inside = test::scratch_path("bad_sets");
  std::filesystem::create_directories(bad_inside);
  test::write_bytes(bad_inside + "/a.json", kGood);
  test::write_bytes(bad_inside + "/b.json", "{");
  EXPECT_TRUE(test::throws_file_error([&] { read_marker_sets(bad_inside); }, bad_inside + "/b.json",
                                      "not valid JSON"));
}

TEST(MarkerSetFile, ReadsEveryFieldWithItsDefaults) {
  const MarkerSet set = read_marker_set(write_set("fields.json", kGood));
  EXPECT_EQ(set.name, "Test set");
  EXPECT_EQ(set.source, "this test");
  ASSERT_EQ(set.markers.size(), 3u);
  const MarkerPlacement& elbow = set.markers[0];
  EXPECT_EQ(elbow.name, "LELB");
  EXPECT_EQ(elbow.aliases, std::vector<std::string>{"LEL"});
  EXPECT_EQ(elbow.description, "left elbow");
  EXPECT_EQ(elbow.bone, "lowerarm01.L");
  EXPECT_EQ(elbow.along, 0.0);
  EXPECT_EQ(elbow.direction, Vec3(-1, 0, 0));  // normalised
  EXPECT_EQ(elbow.radius_mm, 25.0);
  const MarkerPlacement& c7 = set.markers[1];
  EXPECT_EQ(c7.along, 0.5);
  EXPECT_EQ(c7.radius_mm, 30.0);
  EXPECT_NEAR(c7.direction.norm(), 1.0, 1e-15);
  EXPECT_TRUE(c7.aliases.empty());
  const MarkerPlacement& thigh = set.markers[2];
  EXPECT_TRUE(thigh.is_region());
  EXPECT_EQ(thigh.pattern, "thigh_L_*");
  EXPECT_EQ(thigh.bones, std::vector<std::string>{"upperleg*.L"});
  EXPECT_EQ(thigh.side, kFrontSide);
}

}  // namespace
}  // namespace skinstream
