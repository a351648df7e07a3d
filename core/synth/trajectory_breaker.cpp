#include "core/synth/trajectory_breaker.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace skinstream::synth {

namespace {

constexpr int kNone = -2;
constexpr int kGhost = -1;

struct Fragment {
  int marker = 0;
  int first = 0;       // frame
  int last = 0;        // inclusive
  int gap_before = 0;  // missing frames since the marker's previous fragment (-1: none before)
  enum class Fate { kOwn, kUnlabelled, kWrong } fate = Fate::kUnlabelled;
};

double smooth(double u) {
  u = std::clamp(u, 0.0, 1.0);
  return u * u * (3.0 - 2.0 * u);
}

}  // namespace

BreakCounts count_breaks(const Capture& capture, const std::vector<int>& source, int markers) {
  BreakCounts c;
  const int channels = capture.point_count();
  const int frames = capture.frame_count;
  if (source.size() != static_cast<size_t>(channels) * static_cast<size_t>(frames))
    throw std::invalid_argument("count_breaks: source map does not match the capture");
  std::vector<std::vector<char>> delivered(static_cast<size_t>(markers),
                                           std::vector<char>(static_cast<size_t>(frames), 0));
  for (int ch = 0; ch < channels; ++ch) {
    const bool labelled = capture.is_labelled(ch);
    int prev = kNone;
    for (int f = 0; f < frames; ++f) {
      const int s = source[static_cast<size_t>(f) * static_cast<size_t>(channels) + static_cast<size_t>(ch)];
      if (s >= 0 && s < markers) delivered[static_cast<size_t>(s)][static_cast<size_t>(f)] = 1;
      if (s == kGhost) ++c.ghost_samples;
      if (s != kNone && s != prev) {
        ++c.trajectories;
        if (s == kGhost)
          ++c.ghost_trajectories;
        else if (labelled) {
          ++c.labelled_fragments;
          if (s != ch) ++c.wrong_label_fragments;
        } else {
          ++c.unlabelled_fragments;
        }
      }
      prev = s;
    }
  }
  for (int m = 0; m < markers; ++m) {
    bool in_gap = false;
    for (int f = 0; f < frames; ++f) {
      const bool missing = !delivered[static_cast<size_t>(m)][static_cast<size_t>(f)];
      if (missing) {
        ++c.holes;
        if (!in_gap) ++c.gaps;
      }
      in_gap = missing;
    }
  }
  c.missing_fraction = summarize(capture).missing_fraction;
  return c;
}

BrokenCapture break_trajectories(const Capture& truth, const std::vector<uint8_t>& visible,
                                 const std::vector<std::vector<int>>& neighbours, const BreakOptions& o,
                                 Random& rng) {
  const int n = truth.point_count();
  const int frames = truth.frame_count;
  if (static_cast<int>(truth.labelled_points().size()) != n)
    throw std::invalid_argument("break_trajectories: the truth must hold labelled markers only");
  if (visible.size() != static_cast<size_t>(n) * static_cast<size_t>(frames))
    throw std::invalid_argument("break_trajectories: visibility has " + std::to_string(visible.size()) +
                                " entries for " + std::to_string(n) + " markers x " + std::to_string(frames) +
                                " frames");
  if (neighbours.size() != static_cast<size_t>(n))
    throw std::invalid_argument("break_trajectories: one neighbour list per marker needed");
  for (int f = 0; f < frames; ++f)
    for (int i = 0; i < n; ++i)
      if (!truth.present(f, i))
        throw std::invalid_argument("break_trajectories: the truth has a missing sample");
  if (!(truth.rate_hz > 0.0)) throw std::invalid_argument("break_trajectories: the truth has no frame rate");

  const double random_break_per_frame = o.random_breaks_per_s / truth.rate_hz;

  // 1. Fragments: visible runs, cut further by tracking breaks.
  std::vector<Fragment> fragments;
  for (int i = 0; i < n; ++i) {
    std::vector<char> vis(static_cast<size_t>(frames));
    for (int f = 0; f < frames; ++f)
      vis[static_cast<size_t>(f)] = visible[static_cast<size_t>(f) * n + i] != 0;
    if (o.first_frame_complete && frames > 0) vis[0] = 1;
    for (int f = 2; f < frames; ++f) {
      if (!vis[static_cast<size_t>(f)] || !vis[static_cast<size_t>(f - 1)] ||
          !vis[static_cast<size_t>(f - 2)])
        continue;
      const Vec3 predicted = 2.0 * truth.at(f - 1, i) - truth.at(f - 2, i);
      const double err = (truth.at(f, i) - predicted).norm();
      const double p = random_break_per_frame +
                       o.break_max_probability * smooth((err - o.predict_error_lo_mm) /
                                                        (o.predict_error_hi_mm - o.predict_error_lo_mm));
      if (!rng.chance(p)) continue;
      // The trajectory ends at f - 1; the marker is lost for a frame or two (or none: a new
      // trajectory starts right away).
      const int lost = rng.chance(0.4) ? 0 : rng.geometric(std::max(1.0, o.break_dropout_frames));
      if (lost == 0) {
        vis[static_cast<size_t>(f)] = 2;  // marks "new trajectory starts here"
      } else {
        for (int k = 0; k < lost && f + k < frames; ++k) vis[static_cast<size_t>(f + k)] = 0;
        f += lost;
      }
    }
    int previous_last = -1;
    int f = 0;
    while (f < frames) {
      if (!vis[static_cast<size_t>(f)]) {
        ++f;
        continue;
      }
      Fragment frag;
      frag.marker = i;
      frag.first = f;
      frag.gap_before = previous_last < 0 ? (f == 0 ? -1 : f) : f - previous_last - 1;
      ++f;
      while (f < frames && vis[static_cast<size_t>(f)] == 1) ++f;
      frag.last = f - 1;
      previous_last = frag.last;
      fragments.push_back(frag);
    }
  }

  // 2. Labels.
  for (Fragment& fr : fragments) {
    if (fr.first == 0) {
      fr.fate = Fragment::Fate::kOwn;
      continue;
    }
    const bool short_gap = fr.gap_before >= 0 && fr.gap_before <= o.short_gap_frames;
    bool close = false;
    for (int j : neighbours[static_cast<size_t>(fr.marker)])
      if ((truth.at(fr.first, j) - truth.at(fr.first, fr.marker)).norm() < o.close_mm) close = true;
    const double p_wrong = close ? o.wrong_label_close : o.wrong_label;
    const auto& nb = neighbours[static_cast<size_t>(fr.marker)];
    if (!nb.empty() && rng.chance(p_wrong)) {
      fr.fate = Fragment::Fate::kWrong;
    } else if (rng.chance(short_gap ? o.relabel_after_short_gap : o.relabel_after_long_gap)) {
      fr.fate = Fragment::Fate::kOwn;
    } else {
      fr.fate = Fragment::Fate::kUnlabelled;
    }
  }

  // 3. Channels: sources first, positions at the end.
  std::vector<std::vector<int>> channel_source(static_cast<size_t>(n),
                                               std::vector<int>(static_cast<size_t>(frames), kNone));
  for (const Fragment& fr : fragments)
    if (fr.fate == Fragment::Fate::kOwn)
      for (int f = fr.first; f <= fr.last; ++f)
        channel_source[static_cast<size_t>(fr.marker)][static_cast<size_t>(f)] = fr.marker;
  // Wrong labels: a label swap over the fragment's span with a neighbour whose channel holds
  // only that neighbour (or nothing) there. Whatever the neighbour's channel held moves to this
  // marker's channel (empty there: this fragment was not placed). With no such neighbour the
  // fragment stays unlabelled.
  for (Fragment& fr : fragments) {
    if (fr.fate != Fragment::Fate::kWrong) continue;
    auto& mine = channel_source[static_cast<size_t>(fr.marker)];
    std::vector<int> candidates = neighbours[static_cast<size_t>(fr.marker)];
    const int start = candidates.empty() ? 0 : rng.below(static_cast<int>(candidates.size()));
    int chosen = -1;
    for (size_t k = 0; k < candidates.size() && chosen < 0; ++k) {
      const int j = candidates[(static_cast<size_t>(start) + k) % candidates.size()];
      bool clean = true;
      for (int f = fr.first; f <= fr.last && clean; ++f) {
        const int held = channel_source[static_cast<size_t>(j)][static_cast<size_t>(f)];
        clean = (held == kNone || held == j) && mine[static_cast<size_t>(f)] == kNone;
      }
      if (clean) chosen = j;
    }
    if (chosen < 0) {
      fr.fate = Fragment::Fate::kUnlabelled;
      continue;
    }
    auto& theirs = channel_source[static_cast<size_t>(chosen)];
    for (int f = fr.first; f <= fr.last; ++f) {
      mine[static_cast<size_t>(f)] = theirs[static_cast<size_t>(f)];
      theirs[static_cast<size_t>(f)] = fr.marker;
    }
  }
  struct Extra {
    int first, last, source;
    Vec3 offset;
  };
  std::vector<Extra> extras;
  for (const Fragment& fr : fragments)
    if (fr.fate == Fragment::Fate::kUnlabelled)
      extras.push_back({fr.first, fr.last, fr.marker, Vec3::Zero()});
  const double seconds = frames / truth.rate_hz;
  const int ghosts = frames > 0 ? rng.poisson(o.ghosts_per_s * seconds) : 0;
  for (int g = 0; g < ghosts; ++g) {
    const int first = rng.below(frames);
    const int last = std::min(frames - 1, first + rng.geometric(std::max(1.0, o.ghost_frames)) - 1);
    const int near = rng.below(n);
    Vec3 dir(rng.normal(), rng.normal(), rng.normal());
    if (dir.norm() < 1e-9) dir = Vec3::UnitX();
    const Vec3 offset = dir.normalized() * rng.uniform(0.3 * o.ghost_offset_mm, o.ghost_offset_mm);
    extras.push_back({first, last, kGhost - 1 - near, offset});  // remember which marker it shadows
  }
  std::stable_sort(extras.begin(), extras.end(),
                   [](const Extra& a, const Extra& b) { return a.first < b.first; });

  // Unlabelled fragments share channels as C3D files from real systems do: a fragment takes the
  // first channel free since at least one frame before it starts, so two fragments never touch
  // on one channel and each stays a trajectory of its own.
  std::vector<int> slot_of(extras.size());
  std::vector<int> slot_last;
  for (size_t k = 0; k < extras.size(); ++k) {
    int slot = 0;
    while (slot < static_cast<int>(slot_last.size()) && slot_last[slot] >= extras[k].first - 1) ++slot;
    if (slot == static_cast<int>(slot_last.size())) slot_last.push_back(0);
    slot_last[slot] = extras[k].last;
    slot_of[k] = slot;
  }
  std::vector<std::string> labels = truth.labels;
  for (size_t k = 0; k < slot_last.size(); ++k) labels.push_back("*" + std::to_string(k));
  BrokenCapture out;
  out.capture = Capture(labels, frames, truth.rate_hz);
  out.capture.first_frame = truth.first_frame;
  const int channels = out.capture.point_count();
  out.source.assign(static_cast<size_t>(channels) * static_cast<size_t>(frames), kNone);
  auto noisy = [&](const Vec3& p, double sigma) {
    return Vec3(p.x() + sigma * rng.normal(), p.y() + sigma * rng.normal(), p.z() + sigma * rng.normal());
  };
  for (int f = 0; f < frames; ++f) {
    for (int ch = 0; ch < n; ++ch) {
      const int s = channel_source[static_cast<size_t>(ch)][static_cast<size_t>(f)];
      if (s == kNone) continue;
      out.capture.at(f, ch) = noisy(truth.at(f, s), o.noise_mm);
      out.source[static_cast<size_t>(f) * channels + ch] = s;
    }
    for (size_t k = 0; k < extras.size(); ++k) {
      const Extra& e = extras[k];
      if (f < e.first || f > e.last) continue;
      const int ch = n + slot_of[k];
      if (e.source >= 0) {
        out.capture.at(f, ch) = noisy(truth.at(f, e.source), o.noise_mm);
        out.source[static_cast<size_t>(f) * channels + ch] = e.source;
      } else {
        const int near = kGhost - 1 - e.source;
        out.capture.at(f, ch) = noisy(truth.at(f, near) + e.offset, o.ghost_noise_mm);
        out.source[static_cast<size_t>(f) * channels + ch] = kGhost;
      }
    }
  }
  out.counts = count_breaks(out.capture, out.source, n);
  return out;
}

}  // namespace skinstream::synth
