#include "clients/skinstream/synth_evaluation.h"

#include <chrono>
#include <map>

#include "clients/skinstream/json_output.h"
#include "core/capture_filler.h"
#include "core/evaluation/gap_plan.h"
#include "core/evaluation/merge_stats.h"
#include "core/offline/subject_builder.h"

namespace skinstream::cli {
namespace {

// "thigh_R_5" -> "thigh", "abdomen_12" -> "abdomen": the generator's region, sides merged.
std::string synthetic_region(const std::string& name) {
  std::string r = name.substr(0, name.rfind('_'));
  if (r.size() > 2 && (r.ends_with("_L") || r.ends_with("_R"))) r.resize(r.size() - 2);
  return r;
}

// Each wrong fragment: its channel and frames, whose it was and who took it, and whether the two
// are neighbours on the marker surface (a swap between neighbours, or skin touching skin).
nlohmann::ordered_json wrong_fragment_list(const SubjectModel& model, const Capture& delivered,
                                           const std::vector<WrongFragment>& wrong) {
  nlohmann::ordered_json list = nlohmann::ordered_json::array();
  for (const WrongFragment& w : wrong) {
    bool neighbours = false;
    if (w.true_marker >= 0)
      for (int k = model.ring_offsets[w.taken_by]; k < model.ring_offsets[w.taken_by + 1]; ++k)
        neighbours = neighbours || model.ring[k] == w.true_marker;
    list.push_back({{"channel", delivered.labels[w.channel]},
                    {"frames", {w.first_frame, w.last_frame}},
                    {"first_wrong_frame", w.first_wrong_frame},
                    {"wrong_samples", w.wrong_samples},
                    {"true_marker", w.true_marker >= 0 ? model.marker_names[w.true_marker] : "ghost"},
                    {"taken_by", model.marker_names[w.taken_by]},
                    {"how", w.relabelled ? "relabelled" : "measured"},
                    {"neighbours", neighbours}});
  }
  return list;
}

}  // namespace

nlohmann::ordered_json evaluate_on_synthetic(const synth::SynthCapture& take, const synth::SynthCapture& training, int lookahead) {
  const auto start = std::chrono::steady_clock::now();
  SubjectBuildReport build;
  const SubjectModel model = build_subject(training.truth, SubjectBuildOptions{}, nullptr, &build);
  const double build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  std::vector<MarkerStatus> status;
  std::vector<int> fragments;
  CaptureFillReport report;
  const auto fill_start = std::chrono::steady_clock::now();
  CaptureFillOptions fill_options;
  fill_options.lookahead = lookahead;
  const Capture filled = fill_capture(model, take.capture, fill_options, &status, &report, &fragments);
  const double fill_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - fill_start).count();
  const MergeStats merge = merge_stats(take.capture, take.source, map_channels_to_markers(model, take.capture), status, fragments);

  // Hidden then filled: every sample the relabeller could not give a measured point.
  const int n = model.marker_count();
  std::vector<double> mm, normalised;
  std::map<std::string, std::pair<std::vector<double>, std::vector<double>>> by_region;
  for (int f = 0; f < filled.frame_count; ++f)
    for (int m = 0; m < n; ++m) {
      if (is_observed(status[static_cast<size_t>(f) * n + m])) continue;
      const double e = (filled.at(f, m) - take.truth.at(f, m)).norm();
      mm.push_back(e);
      normalised.push_back(e / model.neighbour_distance(m));
      auto& region = by_region[synthetic_region(model.marker_names[m])];
      region.first.push_back(e);
      region.second.push_back(e / model.neighbour_distance(m));
    }
  auto table2 = [](const std::map<std::string, std::pair<std::vector<double>, std::vector<double>>>& errors) {
    nlohmann::ordered_json regions;
    for (const char* name : {"abdomen", "elbow", "thigh", "knee"}) {
      const auto it = errors.find(name);
      if (it == errors.end()) continue;
      regions[name] = {{"mm", to_json(summarize_errors(it->second.first))},
                       {"normalised", to_json(summarize_errors(it->second.second))}};
    }
    return regions;
  };
  const nlohmann::ordered_json regions = table2(by_region);

  // The paper's Table 2 protocol: markers that were seen are deleted and reconstructed. Here
  // seeded gaps (3 frames to 4 s, several markers at once) in the truth of the same take.
  GapPlanOptions plan;
  const std::vector<Gap> gaps = plan_gaps(take.truth, plan);
  const Capture refilled = fill_capture(model, apply_gaps(take.truth, gaps), CaptureFillOptions{});
  std::vector<double> deleted_mm, deleted_normalised;
  std::map<std::string, std::pair<std::vector<double>, std::vector<double>>> deleted_by_region;
  for (const Gap& g : gaps)
    for (int f = g.first_frame; f < g.first_frame + g.length; ++f) {
      const double e = (refilled.at(f, g.point) - take.truth.at(f, g.point)).norm();
      const double nrm = e / model.neighbour_distance(g.point);
      deleted_mm.push_back(e);
      deleted_normalised.push_back(nrm);
      auto& region = deleted_by_region[synthetic_region(model.marker_names[g.point])];
      region.first.push_back(e);
      region.second.push_back(nrm);
    }
  nlohmann::ordered_json j;
  j["training"] = {{"take", "rom, same body, layout and seed"},
                   {"frames", training.frame_count()},
                   {"reference_frame", build.reference_frame},
                   {"mean_ring_size", build.mean_ring_size},
                   {"mean_pca_components", build.mean_pca_components},
                   {"seconds", build_seconds}};
  j["lookahead_frames"] = lookahead;
  j["trajectories_before_merging"] = merge.fragments;
  j["trajectories_after_merging"] = merge.trajectories_after;
  j["after_per_marker"] = static_cast<double>(merge.trajectories_after) / n;
  j["unmerged_fragments"] = merge.unmerged_fragments;
  j["wrongly_labelled_fragments"] = merge.wrong_fragments;
  j["wrongly_labelled_rate"] = merge.wrong_rate();
  j["wrongly_labelled_by"] = {{"measured", merge.wrong_measured_fragments}, {"relabelled", merge.wrong_relabelled_fragments}};
  j["wrongly_labelled_samples"] = merge.wrong_samples;
  j["wrongly_labelled_list"] = wrong_fragment_list(model, take.capture, merge.wrong_list);
  j["true_labels_not_kept"] = merge.true_labels_not_kept;
  j["samples"] = {{"measured", report.measured}, {"relabelled", report.relabelled}, {"filled", report.filled},
                  {"held", report.held}, {"rejected_labels", report.rejected_labels},
                  {"changed_measured", report.changed_measured}};
  j["filled_error"] = {{"metric", "|filled - truth| over samples not measured or relabelled; normalised by the marker's mean one-ring distance in the reference pose"},
                       {"mm", to_json(summarize_errors(mm))},
                       {"normalised", to_json(summarize_errors(normalised))},
                       {"regions", regions}};
  j["deleted_then_filled_error"] = {{"metric", "seeded gaps deleted from the take's truth, filled online; |filled - truth|, normalised as above (the paper's Table 2 protocol)"},
                                    {"gaps", gaps.size()},
                                    {"mm", to_json(summarize_errors(deleted_mm))},
                                    {"normalised", to_json(summarize_errors(deleted_normalised))},
                                    {"regions", table2(deleted_by_region)}};
  j["fill_seconds"] = fill_seconds;
  return j;
}

}  // namespace skinstream::cli
