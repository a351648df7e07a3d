// skinstream eval-fill, run in-process on a real capture with no gaps (CMU 85_02: the first half
// trains the subject, seeded gaps are deleted from the second): every method judged on the same
// deleted samples, the report consistent with itself, the online filler ahead of the baselines.
#include "clients/skinstream/cmd_eval_fill.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <set>

#include "protocol/files/capture_file.h"
#include "support/cli_run.h"
#include "support/test_data.h"
#include "tests/clients/skinstream/command_output.h"

namespace skinstream {
namespace {

using test::kCmu02;

nlohmann::json run_json(cli::EvalFillOptions o) {
  o.json = true;
  const test::CommandOutput r = test::run_command(cli::run_eval_fill, o);
  EXPECT_EQ(r.exit_code, 0);
  return nlohmann::json::parse(r.text);
}

const nlohmann::json& method(const nlohmann::json& report, const std::string& name) {
  for (const auto& m : report["methods"])
    if (m["name"] == name) return m;
  throw std::runtime_error("no method " + name);
}

// Measured when written (seed 3): skinstream online mean 46 mm, linear interpolation 340 mm.
TEST(EvalFillCommand, JudgesEveryMethodOnTheSameDeletedSamples) {
  cli::EvalFillOptions o;
  o.capture_path = kCmu02;
  o.gaps.seed = 3;
  const nlohmann::json j = run_json(o);
  const Capture take = read_capture(kCmu02);
  EXPECT_EQ(j["markers"], static_cast<int>(take.labelled_points().size()));
  EXPECT_EQ(j["train_frames"], static_cast<int>(take.frame_count * 0.5));
  EXPECT_EQ(j["train_frames"].get<int>() + j["test_frames"].get<int>(), take.frame_count);
  EXPECT_EQ(j["gaps"]["protocol"], "short");
  const long deleted = j["gaps"]["samples"];
  ASSERT_GT(deleted, 0);

  std::vector<std::string> names;
  for (const auto& m : j["methods"]) {
    names.push_back(m["name"]);
    EXPECT_EQ(m["unfilled"], 0) << m["name"];
    EXPECT_EQ(m["mm"]["count"].get<long>(), deleted) << m["name"];  // each judged on every deleted sample
  }
  EXPECT_EQ(names, (std::vector<std::string>{"linear", "spline", "gloersen_pca", "skinstream_online", "skinstream_lookahead"}));
  const auto& online = method(j, "skinstream_online");
  EXPECT_EQ(online["changed_measured_samples"], 0);
  EXPECT_LT(online["mm"]["mean"].get<double>(), 0.5 * method(j, "linear")["mm"]["mean"].get<double>());
  EXPECT_LT(online["mm"]["mean"].get<double>(), method(j, "gloersen_pca")["mm"]["mean"].get<double>());
  EXPECT_DOUBLE_EQ(j["online_to_gloersen"]["mean_ratio"].get<double>(),
                   online["mm"]["mean"].get<double>() / method(j, "gloersen_pca")["mm"]["mean"].get<double>());
  EXPECT_EQ(method(j, "skinstream_lookahead")["description"], "skinstream, lookahead 6 frames");
}

TEST(EvalFillCommand, TheSeedPlansTheGapsAndAblationsAddRows) {
  cli::EvalFillOptions o;
  o.capture_path = kCmu02;
  o.gaps.seed = 3;
  o.ablations = true;
  o.lookahead = 12;
  const nlohmann::json a = run_json(o);
  o.gaps.seed = 4;
  const nlohmann::json b = run_json(o);
  EXPECT_EQ(a["methods"].size(), 12u);
  EXPECT_EQ(method(a, "skinstream_lookahead")["description"], "skinstream, lookahead 12 frames");
  EXPECT_NE(a["gaps"]["samples"], b["gaps"]["samples"]);
  std::set<std::string> names;
  for (const auto& m : a["methods"]) names.insert(m["name"].get<std::string>());
  EXPECT_TRUE(names.count("skinstream_rigid_only") && names.count("skinstream_no_carry") &&
              names.count("skinstream_no_region_learning") && names.count("skinstream_no_ring_calibration"));
}

TEST(EvalFillCommand, TheTableHasARowPerMethod) {
  cli::EvalFillOptions o;
  o.capture_path = kCmu02;
  const test::CommandOutput r = test::run_command(cli::run_eval_fill, o);
  ASSERT_EQ(r.exit_code, 0);
  EXPECT_EQ(r.text.rfind(kCmu02 + ": 41 markers", 0), 0u) << r.text;
  for (const char* name : {"\nlinear ", "\nspline ", "\ngloersen_pca ", "\nskinstream_online ", "\nskinstream_lookahead "})
    EXPECT_NE(r.text.find(name), std::string::npos) << name;
  EXPECT_NE(r.text.find("\nonline / Gloersen PCA: mean "), std::string::npos);
}

TEST(EvalFillCommand, RefusesATestPartWithGaps) {
  Capture holed = read_capture(kCmu02);
  holed.at(holed.frame_count - 10, 0) = missing_point();
  const std::string path = test::scratch_path("eval_fill_holed.c3d");
  write_capture(holed, path);
  cli::EvalFillOptions o;
  o.capture_path = path;
  try {
    test::run_command(cli::run_eval_fill, o);
    ADD_FAILURE() << "evaluated against a truth with a gap";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("must have no gaps"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace skinstream
