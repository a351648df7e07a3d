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
  if (!(options.min_seconds >= 0.0) || !std::isfinite(options.min_seconds))
    throw std::invalid_argument("plan_gaps: min_seconds must be finite and not negative");
  if (!(options.max_seconds > 0.0)) throw std::invalid_argument("plan_gaps: max_seconds must be positive");
  if (!(options.gaps_per_marker_per_minute >= 0.0) || !std::isfinite(options.gaps_per_marker_per_minute))
    throw std::invalid_argument("plan_gaps: gaps_per_marker_per_minute must be finite and not negative");
  if (!(options.fraction_of_samples >= 0.0 && options.fraction_of_samples <= 0.5))
    throw std::invalid_argument("plan_gaps: fraction_of_samples must be in [0, 0.5]");
  if (options.markers_per_gap < 1) throw std::invalid_argument("plan_gaps: markers_per_gap must be at least 1");
  if (options.margin_frames < 0) throw std::invalid_argument("plan_gaps: margin_frames must not be negative");
  if (!(full.rate_hz > 0.0) || !std::isfinite(full.rate_hz))
    throw std::invalid_argument("plan_gaps: the capture needs a positive frame rate");
  if (full.frame_count < 0 ||
      full.positions.size() != static_cast<size_t>(full.frame_count) * full.labels.size())
    throw std::invalid_argument("plan_gaps: positions do not match labels x frame_count");
}

// One channel's samples: free, missing (already missing in the capture, or planned), or a
// planned gap's margin. A new gap must lie on free samples; its margins only need to be
// present (margins may share).
class ChannelState {
 public:
  enum : char { free_sample = 0, missing = 1, margin_sample = 2 };

  ChannelState(const Capture& full, int point, int margin) : margin_(margin), state_(full.frame_count) {
    for (int f = 0; f < full.frame_count; ++f) state_[f] = full.present(f, point) ? free_sample : missing;
  }
  // [start, end) with `margin` frames either side, all inside the capture.
  bool fits(int start, int end) const {
    const auto first = state_.begin();
    return std::none_of(first + start, first + end, [](char s) { return s != free_sample; }) &&
           std::none_of(first + (start - margin_), first + start, [](char s) { return s == missing; }) &&
           std::none_of(first + end, first + end + margin_, [](char s) { return s == missing; });
  }
  void take(int start, int end) {
    const auto first = state_.begin();
    std::fill(first + start, first + end, missing);
    std::fill(first + (start - margin_), first + start, margin_sample);
    std::fill(first + end, first + end + margin_, margin_sample);
  }

 private:
  int margin_;
  std::vector<char> state_;
};

}  // namespace

GapPlanOptions long_gap_plan(uint64_t seed) {
  GapPlanOptions o;
  o.seed = seed;
  o.min_seconds = 2.0;
  o.max_seconds = 6.0;
  o.fraction_of_samples = 0.04;
  o.markers_per_gap = 3;
  return o;
}

std::vector<Gap> plan_gaps(const Capture& full, const GapPlanOptions& options) {
  validate(full, options);
  std::mt19937_64 rng(options.seed);
  const int frames = full.frame_count;
  const int shortest = std::max(options.min_frames, static_cast<int>(std::lround(options.min_seconds * full.rate_hz)));
  const int longest = std::max(shortest, static_cast<int>(std::lround(options.max_seconds * full.rate_hz)));
  const int lead = std::max(options.margin_frames, 1);  // frame 0 stays present
  const int margin = options.margin_frames;
  const std::vector<int> points = full.labelled_points();
  std::vector<ChannelState> channels;
  for (int point : points) channels.emplace_back(full, point, margin);
  // A gap's length and a start where it lies inside the capture with its margins; false when
  // the capture is too short for it.
  auto draw_span = [&](int& start, int& length) {
    length = log_uniform_length(rng, shortest, longest);
    const int starts = frames - margin - length - lead + 1;  // start in [lead, frames - margin - length]
    if (starts < 1) return false;
    start = lead + uniform_index(rng, starts);
    return true;
  };

  std::vector<Gap> plan;
  if (options.fraction_of_samples > 0.0) {
    const double target = options.fraction_of_samples * frames * static_cast<double>(points.size());
    long planned = 0;
    std::vector<int> fitting;
    for (int failures = 0; planned < target && failures < 1000;) {
      int start = 0, length = 0;
      fitting.clear();
      if (draw_span(start, length))
        for (size_t c = 0; c < channels.size(); ++c)
          if (channels[c].fits(start, start + length)) fitting.push_back(static_cast<int>(c));
      if (static_cast<int>(fitting.size()) < options.markers_per_gap) {
        ++failures;
        continue;
      }
      failures = 0;
      for (int k = 0; k < options.markers_per_gap; ++k) {
        // A partial Fisher-Yates shuffle: the first k entries are a uniform random choice.
        std::swap(fitting[k], fitting[k + uniform_index(rng, static_cast<int>(fitting.size()) - k)]);
        channels[fitting[k]].take(start, start + length);
        plan.push_back({points[fitting[k]], start, length});
        planned += length;
      }
    }
  } else {
    // More gaps than frames can never fit; the cap keeps absurd rates from looping for long.
    const double expected = std::min(options.gaps_per_marker_per_minute * frames / full.rate_hz / 60.0,
                                     static_cast<double>(frames));
    for (size_t c = 0; c < channels.size(); ++c) {
      const double whole = std::floor(expected);
      const int count = static_cast<int>(whole) + (uniform01(rng) < expected - whole ? 1 : 0);
      for (int g = 0; g < count; ++g)
        for (int attempt = 0; attempt < 100; ++attempt) {
          int start = 0, length = 0;
          if (!draw_span(start, length) || !channels[c].fits(start, start + length)) continue;
          channels[c].take(start, start + length);
          plan.push_back({points[c], start, length});
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
