#include "core/evaluation/fill_error.h"

#include <cmath>
#include <map>
#include <stdexcept>

namespace skinstream {

namespace {

void validate(const Capture& truth, const Capture& filled, const std::vector<Gap>& gaps,
              const std::vector<double>& normaliser) {
  if (truth.point_count() != filled.point_count() || truth.frame_count != filled.frame_count)
    throw std::invalid_argument("fill_error: truth and filled captures differ in channels or frames");
  for (const Capture* capture : {&truth, &filled})
    if (capture->positions.size() != static_cast<size_t>(capture->frame_count) * capture->labels.size())
      throw std::invalid_argument("fill_error: positions do not match labels x frame_count");
  if (normaliser.size() != static_cast<size_t>(truth.point_count()))
    throw std::invalid_argument("fill_error: need one normaliser per channel");
  for (const Gap& gap : gaps) {
    if (gap.point < 0 || gap.point >= truth.point_count() || gap.first_frame < 0 || gap.length < 0 ||
        gap.first_frame + gap.length > truth.frame_count)
      throw std::invalid_argument("fill_error: gap outside the capture");
    const double scale = normaliser[gap.point];
    if (!(scale > 0.0) || !std::isfinite(scale))
      throw std::invalid_argument("fill_error: normaliser of " + truth.labels[gap.point] +
                                  " must be positive and finite");
  }
}

}  // namespace

FillErrorReport fill_error(const Capture& truth, const Capture& filled, const std::vector<Gap>& gaps,
                           const std::vector<double>& normaliser) {
  validate(truth, filled, gaps, normaliser);
  struct Errors {
    std::vector<double> millimetres, normalised;
  };
  Errors all;
  std::map<std::string, Errors> by_region;
  FillErrorReport report;
  for (const Gap& gap : gaps) {
    Errors& region = by_region[marker_region(truth.labels[gap.point])];
    for (int f = gap.first_frame; f < gap.first_frame + gap.length; ++f) {
      if (!truth.present(f, gap.point)) {
        ++report.truth_missing;
        continue;
      }
      if (!filled.present(f, gap.point)) {
        ++report.unfilled;
        continue;
      }
      const double error = (filled.at(f, gap.point) - truth.at(f, gap.point)).norm();
      for (Errors* errors : {&all, &region}) {
        errors->millimetres.push_back(error);
        errors->normalised.push_back(error / normaliser[gap.point]);
      }
    }
  }
  report.millimetres = summarize_errors(all.millimetres);
  report.normalised = summarize_errors(all.normalised);
  for (const std::string& name : marker_regions()) {
    const auto it = by_region.find(name);
    if (it == by_region.end() || it->second.millimetres.empty()) continue;
    report.regions.push_back(
        {name, summarize_errors(it->second.millimetres), summarize_errors(it->second.normalised)});
  }
  return report;
}

}  // namespace skinstream
