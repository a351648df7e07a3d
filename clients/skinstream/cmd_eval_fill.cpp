#include "clients/skinstream/cmd_eval_fill.h"

#include <algorithm>
#include <chrono>
#include <functional>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "clients/skinstream/json_output.h"
#include "core/baselines/cubic_spline_fill.h"
#include "core/baselines/gloersen_pca_fill.h"
#include "core/baselines/linear_interpolation_fill.h"
#include "core/capture_filler.h"
#include "core/evaluation/fill_error.h"
#include "core/offline/subject_builder.h"
#include "protocol/files/capture_file.h"

namespace skinstream::cli {
namespace {

struct FillMethod {
  std::string name;
  std::string description;
  std::function<Capture(const Capture&)> fill;
};

// Samples present in `gapped` that `filled` moved: a measurement the method overruled.
long changed_measured(const Capture& gapped, const Capture& filled) {
  long changed = 0;
  for (size_t k = 0; k < gapped.positions.size(); ++k)
    if (is_present(gapped.positions[k]) && filled.positions[k] != gapped.positions[k]) ++changed;
  return changed;
}

}  // namespace

int run_eval_fill(const EvalFillOptions& o, std::FILE* out) {
  const Capture full = read_capture(o.capture_path);
  Capture train, test;
  if (!o.train_path.empty()) {
    train = read_capture(o.train_path);
    test = full;
  } else {
    const int cut = static_cast<int>(full.frame_count * o.split);
    const std::vector<int> all = [&] {
      std::vector<int> v(full.point_count());
      for (int p = 0; p < full.point_count(); ++p) v[p] = p;
      return v;
    }();
    train = full.select(all, 0, cut);
    test = full.select(all, cut, full.frame_count - cut);
  }
  SubjectBuildReport build_report;
  const SubjectModel model = build_subject(train, SubjectBuildOptions{}, nullptr, &build_report);

  // Truth: the test take's channels of the subject's markers, in the subject's order.
  const std::vector<int> channel_of = map_channels_to_markers(model, test);
  for (int m = 0; m < model.marker_count(); ++m)
    if (channel_of[m] < 0) throw std::runtime_error("test capture has no marker " + model.marker_names[m]);
  const Capture truth = test.select(channel_of, 0, test.frame_count);
  for (int f = 0; f < truth.frame_count; ++f)
    for (int p = 0; p < truth.point_count(); ++p)
      if (!truth.present(f, p)) throw std::runtime_error("--capture must have no gaps in the test part (marker " + truth.labels[p] + ")");

  const GapPlanOptions plan = o.gap_protocol == "long" ? long_gap_plan(o.gaps.seed) : o.gaps;
  const std::vector<Gap> gaps = plan_gaps(truth, plan);
  const Capture gapped = apply_gaps(truth, gaps);
  std::vector<double> normaliser(model.marker_count());
  for (int m = 0; m < model.marker_count(); ++m) normaliser[m] = model.neighbour_distance(m);

  auto skinstream_fill = [&](CaptureFillOptions fill) { return [&model, fill](const Capture& c) { return fill_capture(model, c, fill); }; };
  CaptureFillOptions online, ahead, no_pca, no_continuity, plain_average, no_rigid_fusion, no_carry, no_learning, no_ring_calibration;
  ahead.lookahead = o.lookahead;
  no_pca.filler.use_pca = false;
  no_continuity.filler.continuity_seconds = 0.0;
  plain_average.filler.weight_by_variance = false;
  no_rigid_fusion.filler.fuse_rigid = false;
  no_carry.filler.carry_from_gap_start = false;
  no_learning.filler.learn_regions = false;
  no_ring_calibration.filler.calibrate_rings = false;
  std::vector<FillMethod> methods = {
      {"linear", "linear interpolation (offline)", fill_linear},
      {"spline", "cubic spline (offline)", [](const Capture& c) { return fill_cubic_spline(c); }},
      {"gloersen_pca", "Gloersen & Federolf 2016 PCA (offline)", [](const Capture& c) { return fill_gloersen_pca(c); }},
      {"skinstream_online", "skinstream, lookahead 0 (causal)", skinstream_fill(online)},
      {"skinstream_lookahead", "skinstream, lookahead " + std::to_string(o.lookahead) + " frames", skinstream_fill(ahead)},
  };
  if (o.ablations) {
    methods.push_back({"skinstream_rigid_only", "skinstream online, eq. 2 only (no PCA)", skinstream_fill(no_pca)});
    methods.push_back({"skinstream_no_continuity", "skinstream online, no gap-start continuity", skinstream_fill(no_continuity)});
    methods.push_back({"skinstream_plain_average", "skinstream online, neighbours' PCA estimates averaged unweighted (as the paper)", skinstream_fill(plain_average)});
    methods.push_back({"skinstream_pca_only", "skinstream online, PCA estimates weighted, rigid estimate not fused", skinstream_fill(no_rigid_fusion)});
    methods.push_back({"skinstream_no_carry", "skinstream online, no carry from the gap start by the steadiest anchors", skinstream_fill(no_carry)});
    methods.push_back({"skinstream_no_region_learning", "skinstream online, regions as trained offline (nothing learned online)", skinstream_fill(no_learning)});
    methods.push_back({"skinstream_no_ring_calibration", "skinstream online, one-ring and eq. 2 opinions as calibrated offline (not checked online)", skinstream_fill(no_ring_calibration)});
  }

  long gap_samples = 0;
  int longest = 0;
  for (const Gap& g : gaps) {
    gap_samples += g.length;
    longest = std::max(longest, g.length);
  }
  nlohmann::json report = {
      {"capture", o.capture_path},
      {"train", o.train_path.empty() ? o.capture_path + " (first " + std::to_string(o.split) + ")" : o.train_path},
      {"seed", o.gaps.seed},
      {"markers", model.marker_count()},
      {"train_frames", train.frame_count},
      {"test_frames", truth.frame_count},
      {"rate_hz", truth.rate_hz},
      {"gaps", {{"protocol", o.gap_protocol}, {"count", gaps.size()}, {"samples", gap_samples}, {"longest_frames", longest},
                {"fraction_of_samples", double(gap_samples) / (double(truth.frame_count) * truth.point_count())}}},
      {"metric", "error = |filled - truth| over deleted samples; normalised = error / the marker's mean distance to its one-ring in the reference pose (Park & Hodgins Table 2); changed_measured_samples: samples left in the capture that the method moved"},
      {"methods", nlohmann::json::array()}};
  for (const FillMethod& method : methods) {
    const auto start = std::chrono::steady_clock::now();
    const Capture filled = method.fill(gapped);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const FillErrorReport r = fill_error(truth, filled, gaps, normaliser);
    nlohmann::json regions = nlohmann::json::object();
    for (const RegionFillError& region : r.regions)
      regions[region.region] = {{"mm", to_json(region.millimetres)}, {"normalised", to_json(region.normalised)}};
    report["methods"].push_back({{"name", method.name}, {"description", method.description}, {"mm", to_json(r.millimetres)},
                                 {"normalised", to_json(r.normalised)}, {"unfilled", r.unfilled}, {"regions", regions},
                                 {"changed_measured_samples", changed_measured(gapped, filled)}, {"seconds", seconds}});
  }
  // The online filler against the offline Gloersen PCA on the same gaps.
  auto errors_of = [&](const std::string& name) {
    for (const auto& m : report["methods"])
      if (m["name"] == name) return m["mm"];
    throw std::logic_error("no method " + name);
  };
  const nlohmann::json offline_pca = errors_of("gloersen_pca"), causal = errors_of("skinstream_online");
  report["online_to_gloersen"] = {{"mean_ratio", causal["mean"].get<double>() / offline_pca["mean"].get<double>()},
                                  {"max_ratio", causal["max"].get<double>() / offline_pca["max"].get<double>()}};
  if (o.json) {
    std::fprintf(out, "%s\n", report.dump(2).c_str());
    return 0;
  }
  std::fprintf(out, "%s: %d markers, %d test frames, %zu gaps (%ld samples, longest %d frames)\n", o.capture_path.c_str(),
               model.marker_count(), truth.frame_count, gaps.size(), gap_samples, longest);
  std::fprintf(out, "%-31s %9s %9s %9s %9s %10s %10s %8s\n", "method", "mean mm", "median", "p95", "max", "mean norm", "max norm",
               "changed");
  for (const auto& m : report["methods"])
    std::fprintf(out, "%-31s %9.2f %9.2f %9.2f %9.2f %10.4f %10.4f %8ld\n", m["name"].get<std::string>().c_str(),
                 m["mm"]["mean"].get<double>(), m["mm"]["median"].get<double>(), m["mm"]["p95"].get<double>(),
                 m["mm"]["max"].get<double>(), m["normalised"]["mean"].get<double>(), m["normalised"]["max"].get<double>(),
                 m["changed_measured_samples"].get<long>());
  std::fprintf(out, "online / Gloersen PCA: mean %.2f, max %.2f\n", report["online_to_gloersen"]["mean_ratio"].get<double>(),
               report["online_to_gloersen"]["max_ratio"].get<double>());
  return 0;
}

}  // namespace skinstream::cli
