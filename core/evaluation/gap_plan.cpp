#include "core/evaluation/gap_plan.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

namespace skinstream {

namespace {

// 53 random bits -> [0, 1); identical on every platform, unlike std::uniform_real_distribution.
double uniform01(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

// Uniform integer in [0, count); the bias of scaling a 53-bit fraction is far below any use here.
int uniform_index(std::mt19937_64& rng, int count) {
  return std::min(count - 1, static_cast<int>(uniform01(rng) * count));
}

int log_uniform_length(std::mt19937_64& rng, int shortest, int longest) {
  const double ratio = static_cast<double>(longest + 1) / shortest;
  const int length = static_cast<int>(std::floor(shortest * std::pow(ratio, uniform01(rng))));
  return std::clamp(length, shortest, longest);
}

void validate(const Capture& full, const GapPlanOptions& options) {
  if (options.min_frames < 1) throw std::invalid_argument("plan_gaps: min_frames must be at least 1");
  if (!(options.max_seconds > 0.0)) throw std::invalid_argument("plan_gaps: max_seconds must be positive");
  if (!(options.gaps_per_marker_per_minute >= 0.0) || !std::isfinite(options.gaps_per_marker_per_minute))
    throw std::invalid_argument("plan_gaps: gaps_per_marker_per_minute must be finite and not negative");
  if (options.margin_frames < 0) throw std::invalid_argument("plan_gaps: margin_frames must not be negative");
  if (!(full.rate_hz > 0.0) || !std::isfinite(full.rate_hz))
    throw std::invalid_argument("plan_gaps: the capture needs a positive frame rate");
  if (full.frame_count < 0 ||
      full.positions.size() != static_cast<size_t>(full.frame_count) * full.labels.size())
    throw std::invalid_argument("plan_gaps: positions do not match labels x frame_count");
}

}  // namespace

std::vector<Gap> plan_gaps(const Capture& full, const GapPlanOptions& options) {
  validate(full, options);
  std::mt19937_64 rng(options.seed);
  const int frames = full.frame_count;
  const int longest =
      std::max(options.min_frames, static_cast<int>(std::lround(options.max_seconds * full.rate_hz)));
  // More gaps than frames can never fit; the cap keeps absurd rates from looping for long.
  const double expected = std::min(options.gaps_per_marker_per_minute * frames / full.rate_hz / 60.0,
                                   static_cast<double>(frames));
  const int lead = std::max(options.margin_frames, 1);  // frame 0 stays present
  const int margin = options.margin_frames;

  std::vector<Gap> plan;
  for (int point : full.labelled_points()) {
    // state[f]: free, missing (already missing in `full` or planned), or a planned gap's margin.
    // A new gap must lie on free samples; its margins only need to be present (margins may share).
    enum : char { free_sample = 0, missing = 1, margin_sample = 2 };
    std::vector<char> state(frames);
    for (int f = 0; f < frames; ++f) state[f] = full.present(f, point) ? free_sample : missing;
    const double whole = std::floor(expected);
    const int count = static_cast<int>(whole) + (uniform01(rng) < expected - whole ? 1 : 0);
    for (int g = 0; g < count; ++g) {
      for (int attempt = 0; attempt < 100; ++attempt) {
        const int length = log_uniform_length(rng, options.min_frames, longest);
        const int starts = frames - margin - length - lead + 1;  // start in [lead, frames - margin - length]
        if (starts < 1) continue;
        const int start = lead + uniform_index(rng, starts);
        const int end = start + length;  // exclusive
        const auto first = state.begin();
        if (std::any_of(first + start, first + end, [](char s) { return s != free_sample; })) continue;
        if (std::any_of(first + (start - margin), first + start, [](char s) { return s == missing; }))
          continue;
        if (std::any_of(first + end, first + end + margin, [](char s) { return s == missing; })) continue;
        std::fill(first + start, first + end, missing);
        std::fill(first + (start - margin), first + start, margin_sample);
        std::fill(first + end, first + end + margin, margin_sample);
        plan.push_back({point, start, length});
        break;
      }
    }
  }
  std::sort(plan.begin(), plan.end(), [](const Gap& a, const Gap& b) {
    return a.point != b.point ? a.point < b.point : a.first_frame < b.first_frame;
  });
  return plan;
}

Capture apply_gaps(const Capture& capture, const std::vector<Gap>& gaps) {
  Capture out = capture;
  for (const Gap& gap : gaps) {
    if (gap.length < 1) throw std::invalid_argument("apply_gaps: gap length must be at least 1");
    if (gap.point < 0 || gap.point >= capture.point_count() || gap.first_frame < 0 ||
        gap.first_frame + gap.length > capture.frame_count)
      throw std::out_of_range("apply_gaps: gap outside the capture");
    for (int f = gap.first_frame; f < gap.first_frame + gap.length; ++f)
      out.at(f, gap.point) = missing_point();
  }
  return out;
}

}  // namespace skinstream
