// The SubjectRouter on hand-made SourceFrames: two actors wearing one marker template never mix,
// an unnamed subject follows every source subject carrying its labels, a named one is reported
// absent and then present, unlabelled points go to one subject each, non-finite points are
// refused, a source inventing names every frame grows neither memory nor reports, and routing
// allocates nothing once matched.
#include "server/ingest/subject_router.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>

#include "support/allocation_counter.h"

namespace skinstream::server {
namespace {

struct Recorder : SubjectRouter::Observer {
  struct Match {
    int target;
    bool present;
    std::string detail;
  };
  void on_match(int target, bool present, std::string_view detail) override { matches.push_back({target, present, std::string(detail)}); }
  void on_unknown_subjects(std::span<const std::string> names, size_t not_listed) override {
    unknown_subjects.insert(unknown_subjects.end(), names.begin(), names.end());
    subjects_not_listed += not_listed;
    ++unknown_subject_calls;
  }
  void on_unknown_labels(int target, std::span<const std::string> names, size_t not_listed) override {
    for (const std::string& n : names) unknown_labels[target].push_back(n);
    labels_not_listed += not_listed;
  }
  std::vector<Match> matches;
  std::vector<std::string> unknown_subjects;
  size_t subjects_not_listed = 0, unknown_subject_calls = 0, labels_not_listed = 0;
  std::map<int, std::vector<std::string>> unknown_labels;
};

const std::vector<std::string> kTemplate = {"LFHD", "RFHD", "C7", "STRN"};

// A source subject wearing `labels`, its markers at x = `centre` (y 0, 100, 200, ... mm by label).
void add_subject(SourceFrame& frame, const std::string& name, double centre, std::vector<std::string> labels = kTemplate) {
  SourceSubject& s = frame.subjects.emplace_back();
  s.name = name;
  s.labels = std::move(labels);
  std::vector<Vec3>& positions = frame.labelled.emplace_back();
  for (size_t l = 0; l < s.labels.size(); ++l) positions.emplace_back(centre, 100.0 * static_cast<double>(l), 1000.0);
  ++frame.structure_version;
}

// Routes `frame` to every target; returns the frames (index = target).
struct Routed {
  std::vector<MarkerFrame> frames;
  SubjectRouter::Stats stats;
};
Routed route(SubjectRouter& router, const SourceFrame& frame) {
  Routed r;
  for (int t = 0; t < router.target_count(); ++t) r.frames.emplace_back(static_cast<int>(router.target(t).marker_names.size()));
  std::vector<MarkerFrame*> out;
  for (MarkerFrame& f : r.frames) out.push_back(&f);
  r.stats = router.route(frame, out);
  return r;
}

// Actor1 at x = -2 m wearing the template and `extra`, a label the subject file lacks; Actor2 at
// +2 m wearing the template.
SourceFrame two_actors_one_with(const std::string& extra) {
  SourceFrame frame;
  std::vector<std::string> labels = kTemplate;
  labels.push_back(extra);
  add_subject(frame, "Actor1", -2000.0, labels);
  add_subject(frame, "Actor2", 2000.0);
  return frame;
}

TEST(SubjectRouter, TwoActorsWithOneTemplateNeverMix) {
  for (bool actor2_first : {false, true}) {
    SCOPED_TRACE(actor2_first ? "Actor2 listed first" : "Actor1 listed first");
    SourceFrame frame;
    if (actor2_first) add_subject(frame, "Actor2", 2000.0);
    add_subject(frame, "Actor1", -2000.0);
    if (!actor2_first) add_subject(frame, "Actor2", 2000.0);
    Recorder recorder;
    SubjectRouter router({{"Actor1", kTemplate}, {"Actor2", kTemplate}}, recorder);
    const Routed r = route(router, frame);
    ASSERT_TRUE(router.present(0));
    ASSERT_TRUE(router.present(1));
    for (int m = 0; m < 4; ++m) {
      EXPECT_EQ(r.frames[0].labelled[m].x(), -2000.0) << kTemplate[m];
      EXPECT_EQ(r.frames[1].labelled[m].x(), 2000.0) << kTemplate[m];
    }
    EXPECT_EQ(r.frames[0].unlabelled_count + r.frames[1].unlabelled_count, 0);
    ASSERT_EQ(recorder.matches.size(), 2u);
    EXPECT_NE(recorder.matches[0].detail.find("follows \"Actor1\": 4 of the subject's 4 markers"), std::string::npos)
        << recorder.matches[0].detail;
  }
}

TEST(SubjectRouter, UnnamedSubjectFollowsEverySubjectCarryingItsLabelsAndIgnoresOthers) {
  SourceFrame frame;
  add_subject(frame, "Head", 0.0, {"LFHD", "RFHD"});  // one body split over two source subjects
  add_subject(frame, "Torso", 0.0, {"C7", "STRN", "EXTRA"});
  add_subject(frame, "Prop", 0.0, {"TIP", "HANDLE"});  // another object: none of ours
  Recorder recorder;
  SubjectRouter router({{"", kTemplate}}, recorder);
  const Routed r = route(router, frame);
  ASSERT_TRUE(router.present(0));
  for (int m = 0; m < 4; ++m) EXPECT_TRUE(is_present(r.frames[0].labelled[m])) << kTemplate[m];
  EXPECT_EQ(r.frames[0].labelled[2], frame.labelled[1][0]);  // C7 from Torso
  // EXTRA is a label of a followed subject the file lacks: an unlabelled point of this subject.
  ASSERT_EQ(r.frames[0].unlabelled_count, 1);
  EXPECT_EQ(r.frames[0].unlabelled[0], frame.labelled[1][2]);
  EXPECT_EQ(r.frames[0].unknown_labels, 1);
  EXPECT_EQ(recorder.unknown_labels[0], std::vector<std::string>{"EXTRA"});
  EXPECT_EQ(recorder.unknown_subjects, std::vector<std::string>{"Prop"});
  // Reported once: the same structure again says nothing new.
  frame.structure_version += 1;
  route(router, frame);
  EXPECT_EQ(recorder.unknown_subjects.size(), 1u);
  EXPECT_EQ(recorder.unknown_labels[0].size(), 1u);
  EXPECT_EQ(recorder.matches.size(), 1u);
}

TEST(SubjectRouter, UnnamedSubjectWithTwoActorsTakesTheFirstAndSaysHowToChoose) {
  SourceFrame frame;
  add_subject(frame, "Actor1", -2000.0);
  add_subject(frame, "Actor2", 2000.0);
  frame.labelled[0][1] = missing_point();  // Actor1's RFHD occluded: Actor2's must not stand in
  Recorder recorder;
  SubjectRouter router({{"", kTemplate}}, recorder);
  const Routed r = route(router, frame);
  EXPECT_EQ(r.frames[0].labelled[0].x(), -2000.0);
  EXPECT_FALSE(is_present(r.frames[0].labelled[1]));
  EXPECT_EQ(r.frames[0].unlabelled_count, 0);  // Actor2's labels are another body's, not free points
  ASSERT_EQ(recorder.matches.size(), 1u);
  EXPECT_NE(recorder.matches[0].detail.find("--subject NAME=FILE"), std::string::npos) << recorder.matches[0].detail;
}

TEST(SubjectRouter, NamedSubjectAbsentThenPresentThenGone) {
  Recorder recorder;
  SubjectRouter router({{"Actor1", kTemplate}, {"Actor2", kTemplate}}, recorder);
  SourceFrame frame;
  add_subject(frame, "Actor1", -2000.0);
  Routed r = route(router, frame);
  EXPECT_TRUE(router.present(0));
  EXPECT_FALSE(router.present(1));
  EXPECT_EQ(r.frames[1].frame_number, 0u);  // not filled
  ASSERT_EQ(recorder.matches.size(), 2u);
  EXPECT_FALSE(recorder.matches[1].present);
  EXPECT_EQ(recorder.matches[1].detail, "the stream has no subject \"Actor2\" (it has \"Actor1\")");

  frame.frame_number = 7;
  add_subject(frame, "Actor2", 2000.0);  // walks on
  r = route(router, frame);
  EXPECT_TRUE(router.present(1));
  EXPECT_EQ(r.frames[1].frame_number, 7u);
  EXPECT_EQ(r.frames[1].labelled[0].x(), 2000.0);
  ASSERT_EQ(recorder.matches.size(), 3u);
  EXPECT_TRUE(recorder.matches[2].present);
  EXPECT_EQ(recorder.matches[2].target, 1);

  frame.subjects.erase(frame.subjects.begin());  // Actor1 leaves
  frame.labelled.erase(frame.labelled.begin());
  ++frame.structure_version;
  r = route(router, frame);
  EXPECT_FALSE(router.present(0));
  EXPECT_TRUE(router.present(1));
  EXPECT_EQ(r.frames[1].labelled[0].x(), 2000.0);
  ASSERT_EQ(recorder.matches.size(), 4u);
  EXPECT_EQ(recorder.matches[3].target, 0);
  EXPECT_FALSE(recorder.matches[3].present);
}

TEST(SubjectRouter, UnlabelledPointsGoToTheNearestSubjectAndNeverToTwo) {
  Recorder recorder;
  SubjectRouter router({{"Actor1", kTemplate}, {"Actor2", kTemplate}}, recorder);
  SourceFrame frame;
  add_subject(frame, "Actor1", -2000.0);
  add_subject(frame, "Actor2", 2000.0);
  // Near Actor1's markers, near Actor2's, and two just either side of the middle.
  frame.unlabelled = {Vec3(-1990, 110, 1000), Vec3(2015, 190, 1000), Vec3(-1, 0, 1000), Vec3(1, 0, 1000)};
  frame.unlabelled_ids = {10, 20, 30, 40};
  Routed r = route(router, frame);
  auto ids = [](const MarkerFrame& f) { return std::vector<int>(f.unlabelled_ids.begin(), f.unlabelled_ids.begin() + f.unlabelled_count); };
  EXPECT_EQ(ids(r.frames[0]), (std::vector<int>{10, 30}));
  EXPECT_EQ(ids(r.frames[1]), (std::vector<int>{20, 40}));
  EXPECT_EQ(r.frames[0].unlabelled[0], frame.unlabelled[0]);

  // Actor1 occluded entirely this frame: its markers' last positions still claim its points.
  for (Vec3& p : frame.labelled[0]) p = missing_point();
  r = route(router, frame);
  EXPECT_EQ(ids(r.frames[0]), (std::vector<int>{10, 30}));
  EXPECT_EQ(ids(r.frames[1]), (std::vector<int>{20, 40}));

  // With one subject in the stream, every point is its.
  SubjectRouter alone({{"Actor2", kTemplate}}, recorder);
  r = route(alone, frame);
  EXPECT_EQ(ids(r.frames[0]), (std::vector<int>{10, 20, 30, 40}));
}

TEST(SubjectRouter, UnknownLabelsStayWithTheirOwnSubject) {
  Recorder recorder;
  SubjectRouter router({{"Actor1", kTemplate}, {"Actor2", kTemplate}}, recorder);
  SourceFrame frame = two_actors_one_with("LWRB");
  frame.labelled[0][4] = Vec3(1999, 0, 1000);  // Actor1's LWRB, though it lies next to Actor2
  const Routed r = route(router, frame);
  ASSERT_EQ(r.frames[0].unlabelled_count, 1);
  EXPECT_EQ(r.frames[0].unlabelled[0], Vec3(1999, 0, 1000));
  EXPECT_EQ(r.frames[0].unlabelled_ids[0], SubjectRouter::kUnknownLabelIds - 4);
  EXPECT_EQ(r.frames[1].unlabelled_count, 0);
}

TEST(SubjectRouter, NonFinitePointsAreRefusedAndCounted) {
  Recorder recorder;
  SubjectRouter router({{"", kTemplate}}, recorder);
  SourceFrame frame;
  add_subject(frame, "Actor1", 0.0);
  const double inf = std::numeric_limits<double>::infinity();
  frame.labelled[0][0] = missing_point();      // occluded: not an error
  frame.labelled[0][1] = Vec3(inf, 0, 0);      // broken
  frame.labelled[0][2] = Vec3(std::nan(""), 1, 2);  // half a point: broken
  frame.unlabelled = {Vec3(inf, 0, 0), Vec3(5, 5, 5)};
  frame.unlabelled_ids = {1, 2};
  const Routed r = route(router, frame);
  EXPECT_EQ(r.frames[0].rejected_points, 2);
  EXPECT_EQ(r.stats.rejected_points, 1);
  for (int m = 0; m < 3; ++m) EXPECT_FALSE(is_present(r.frames[0].labelled[m])) << m;
  EXPECT_TRUE(is_present(r.frames[0].labelled[3]));
  ASSERT_EQ(r.frames[0].unlabelled_count, 1);
  EXPECT_EQ(r.frames[0].unlabelled_ids[0], 2);
}

// Finite but absurd: 3.4e38 mm (QTM's float maximum), 1e39 mm (1e36 m over NatNet), 1e7 mm (10
// km): no stage is that large. Missing and counted, as the non-finite are; the box they would
// have spread for the unlabelled points is not touched.
TEST(SubjectRouter, PointsOutsideTheCaptureVolumeAreMissingAndCounted) {
  Recorder recorder;
  SubjectRouter router({{"Actor1", kTemplate}, {"Actor2", kTemplate}}, recorder, 50'000.0);
  SourceFrame frame = two_actors_one_with("X");
  frame.labelled[0][0] = Vec3(3.4e38, 0, 0);
  frame.labelled[0][1] = Vec3(0, -1e39, 0);
  frame.labelled[0][2] = Vec3(0, 0, 1e7);
  frame.labelled[1][3] = Vec3(50'000.0, -50'000.0, 0);  // at the edge: still a position
  frame.unlabelled = {Vec3(1e7, 0, 0), Vec3(-2000, 50, 1000)};
  frame.unlabelled_ids = {1, 2};
  const Routed r = route(router, frame);
  EXPECT_EQ(r.frames[0].implausible_points, 3);
  EXPECT_EQ(r.frames[0].rejected_points, 0);
  EXPECT_EQ(r.stats.implausible_points, 1);
  EXPECT_EQ(r.stats.rejected_points, 0);
  for (int m = 0; m < 3; ++m) EXPECT_FALSE(is_present(r.frames[0].labelled[m])) << m;
  EXPECT_EQ(r.frames[1].labelled[3], Vec3(50'000.0, -50'000.0, 0));
  // The one plausible unlabelled point went to Actor1, whose box the absurd markers did not stretch.
  ASSERT_EQ(r.frames[0].unlabelled_count, 2);  // its own unknown label "X" and the point
  EXPECT_EQ(r.frames[0].unlabelled_ids[1], 2);
  EXPECT_EQ(r.frames[1].unlabelled_count, 0);
}

TEST(SubjectRouter, PositionsThatDoNotMatchTheLabelsAreSkipped) {
  Recorder recorder;
  SubjectRouter router({{"Actor1", kTemplate}}, recorder);
  SourceFrame frame;
  add_subject(frame, "Actor1", 0.0);
  frame.labelled[0].resize(2);  // a broken source: fewer positions than labels
  Routed r = route(router, frame);
  EXPECT_TRUE(is_present(r.frames[0].labelled[1]));
  EXPECT_FALSE(is_present(r.frames[0].labelled[2]));
  frame.labelled.clear();  // none at all
  r = route(router, frame);
  for (int m = 0; m < 4; ++m) EXPECT_FALSE(is_present(r.frames[0].labelled[m]));
}

TEST(SubjectRouter, ASourceInventingNamesEveryFrameIsBounded) {
  Recorder recorder;
  SubjectRouter router({{"Actor1", kTemplate}}, recorder);
  constexpr int kFrames = 20, kNamesPerFrame = 10000;
  for (int f = 0; f < kFrames; ++f) {
    SourceFrame frame;
    frame.structure_version = static_cast<uint64_t>(f + 1);
    add_subject(frame, "Actor1", 0.0, {"LFHD", "RFHD", "C7", "STRN", "new_label_" + std::to_string(f)});
    frame.subjects.reserve(kNamesPerFrame + 1);
    for (int n = 0; n < kNamesPerFrame; ++n) frame.subjects.push_back({"intruder_" + std::to_string(f) + "_" + std::to_string(n), {}});
    frame.labelled.resize(frame.subjects.size());
    frame.structure_version = static_cast<uint64_t>(f + 1);
    route(router, frame);
  }
  EXPECT_EQ(router.remembered_subject_names(), SubjectRouter::kMaxRememberedNames);
  EXPECT_EQ(recorder.unknown_subjects.size(), SubjectRouter::kMaxRememberedNames);
  EXPECT_EQ(recorder.subjects_not_listed, static_cast<size_t>(kFrames) * kNamesPerFrame - SubjectRouter::kMaxRememberedNames);
  EXPECT_EQ(recorder.unknown_subject_calls, static_cast<size_t>(kFrames));  // one report per change, not per name
  EXPECT_TRUE(router.present(0));
  EXPECT_EQ(recorder.matches.size(), 1u);
  EXPECT_EQ(recorder.unknown_labels[0].size(), static_cast<size_t>(kFrames));
  // The match's detail lists a few names, not ten thousand.
  SubjectRouter absent({{"Nobody", kTemplate}}, recorder);
  SourceFrame crowd;
  for (int n = 0; n < kNamesPerFrame; ++n) crowd.subjects.push_back({std::string(1000, 'x') + std::to_string(n), {}});
  crowd.labelled.resize(crowd.subjects.size());
  crowd.structure_version = 1;
  route(absent, crowd);
  ASSERT_FALSE(recorder.matches.empty());
  EXPECT_LT(recorder.matches.back().detail.size(), 1000u);
  EXPECT_NE(recorder.matches.back().detail.find("and 9992 more"), std::string::npos);
}

TEST(SubjectRouter, RoutingAllocatesNothingOnceMatched) {
  Recorder recorder;
  SubjectRouter router({{"Actor1", kTemplate}, {"Actor2", kTemplate}}, recorder);
  SourceFrame frame = two_actors_one_with("EXTRA");
  frame.unlabelled = {Vec3(-1990, 0, 1000), Vec3(1990, 0, 1000)};
  frame.unlabelled_ids = {1, 2};
  MarkerFrame a(4), b(4);
  MarkerFrame* const out[] = {&a, &b};
  router.route(frame, out);  // matches (allocates)
  size_t allocations = 0;
  {
    test::CountAllocations count;
    for (uint32_t f = 0; f < 100; ++f) {
      frame.frame_number = f;
      router.route(frame, out);
    }
    allocations = count.count();
  }
  EXPECT_EQ(allocations, 0u);
  EXPECT_EQ(a.frame_number, 99u);
  EXPECT_EQ(a.unlabelled_count, 2);  // EXTRA and the point near Actor1
  EXPECT_EQ(b.unlabelled_count, 1);
}

}  // namespace
}  // namespace skinstream::server
