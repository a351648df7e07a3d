#include "server/ingest/subject_router.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace skinstream::server {
namespace {

// "A", "B" and 9998 more: a list for a log line that a hostile source cannot make long.
template <typename Name>
std::string quoted_list(size_t count, Name name_of) {
  constexpr size_t kListed = 8, kLongestName = 64;
  std::string out;
  for (size_t i = 0; i < count && i < kListed; ++i) out += (i > 0 ? ", \"" : "\"") + name_of(i).substr(0, kLongestName) + "\"";
  if (count > kListed) out += " and " + std::to_string(count - kListed) + " more";
  return out;
}

std::string quoted(const std::vector<std::string>& names) {
  return quoted_list(names.size(), [&](size_t i) { return names[i]; });
}

std::string quoted(const std::vector<SourceSubject>& subjects) {
  if (subjects.empty()) return "no subjects";
  return quoted_list(subjects.size(), [&](size_t i) { return subjects[i].name; });
}

// Distance from p to the box [lo, hi] (0 inside).
double box_distance(const Vec3& p, const Vec3& lo, const Vec3& hi) {
  return (p.cwiseMax(lo).cwiseMin(hi) - p).norm();
}

void add_unlabelled(MarkerFrame& out, const Vec3& p, int id) {
  if (out.unlabelled_count >= MarkerFrame::kMaxUnlabelled) {
    ++out.rejected_points;
    return;
  }
  out.unlabelled[static_cast<size_t>(out.unlabelled_count)] = p;
  out.unlabelled_ids[static_cast<size_t>(out.unlabelled_count)] = id;
  ++out.unlabelled_count;
}

}  // namespace

SubjectRouter::Target::Target(SubjectTarget c) : config(std::move(c)) {
  for (size_t m = 0; m < config.marker_names.size(); ++m) marker_index.emplace(config.marker_names[m], static_cast<int>(m));
  last_seen.assign(config.marker_names.size(), missing_point());
}

SubjectRouter::SubjectRouter(std::vector<SubjectTarget> targets, Observer& observer, double max_coordinate_mm)
    : observer_(observer), max_coordinate_mm_(max_coordinate_mm) {
  targets_.reserve(targets.size());
  for (SubjectTarget& t : targets) targets_.emplace_back(std::move(t));
  candidates_.reserve(targets_.size());
}

void SubjectRouter::replace_target(int t, SubjectTarget target) {
  targets_[static_cast<size_t>(t)] = Target(std::move(target));
  matched_ = false;
}

void SubjectRouter::add_target(SubjectTarget target) {
  targets_.emplace_back(std::move(target));
  candidates_.reserve(targets_.size());
  matched_ = false;
}

void SubjectRouter::remove_target(int t) {
  targets_.erase(targets_.begin() + t);
  matched_ = false;
}

int SubjectRouter::markers_labelled_by(int t, const SourceSubject& subject) const {
  const Target& target = targets_[static_cast<size_t>(t)];
  std::vector<char> labelled(target.config.marker_names.size(), 0);
  for (const std::string& label : subject.labels)
    if (const auto it = target.marker_index.find(label); it != target.marker_index.end()) labelled[static_cast<size_t>(it->second)] = 1;
  return static_cast<int>(std::count(labelled.begin(), labelled.end(), 1));
}

void SubjectRouter::rematch(const SourceFrame& frame) {
  matched_ = true;
  structure_version_ = frame.structure_version;
  std::vector<char> followed_by_any(frame.subjects.size(), 0);
  for (size_t t = 0; t < targets_.size(); ++t) match(targets_[t], static_cast<int>(t), frame.subjects, followed_by_any);

  std::vector<std::string> new_names;
  size_t not_listed = 0;
  for (size_t s = 0; s < frame.subjects.size(); ++s) {
    if (followed_by_any[s]) continue;
    switch (unknown_subjects_.insert(frame.subjects[s].name)) {
      case BoundedNameSet::Insert::New: new_names.push_back(frame.subjects[s].name); break;
      case BoundedNameSet::Insert::Full: ++not_listed; break;
      case BoundedNameSet::Insert::Known: break;
    }
  }
  if (!new_names.empty() || not_listed > 0) observer_.on_unknown_subjects(new_names, not_listed);
}

void SubjectRouter::match(Target& target, int index, const std::vector<SourceSubject>& subjects,
                          std::vector<char>& followed_by_any) {
  std::vector<std::string> followed;
  target.slots.clear();
  std::vector<size_t> taken_by(target.config.marker_names.size(), 0);  // source subject + 1, 0: not taken
  bool shared_labels = false;
  std::vector<std::string> new_labels;
  size_t labels_not_listed = 0;
  for (size_t s = 0; s < subjects.size(); ++s) {
    const SourceSubject& subject = subjects[s];
    if (!target.config.name.empty()) {
      // Named: that subject and no other (the first, should a source repeat a name).
      if (subject.name != target.config.name || !followed.empty()) continue;
    } else if (markers_labelled_by(index, subject) == 0) {
      continue;
    }
    followed.push_back(subject.name);
    followed_by_any[s] = 1;
    for (size_t l = 0; l < subject.labels.size(); ++l) {
      const auto it = target.marker_index.find(subject.labels[l]);
      const size_t taker = it == target.marker_index.end() ? 0 : taken_by[static_cast<size_t>(it->second)];
      // A label already taken by an earlier subject is another body's: left out.
      if (taker != 0 && taker != s + 1) {
        shared_labels = true;
        continue;
      }
      // Unknown, or a label its own subject repeats: an unlabelled point of this subject.
      if (it == target.marker_index.end() || taker == s + 1) {
        target.slots.push_back({s, l, kUnknownLabel});
        if (taker == s + 1) continue;
        switch (target.unknown_labels.insert(subject.labels[l])) {
          case BoundedNameSet::Insert::New: new_labels.push_back(subject.labels[l]); break;
          case BoundedNameSet::Insert::Full: ++labels_not_listed; break;
          case BoundedNameSet::Insert::Known: break;
        }
        continue;
      }
      taken_by[static_cast<size_t>(it->second)] = s + 1;
      target.slots.push_back({s, l, it->second});
    }
  }
  const bool present = !followed.empty();
  if (!present) {
    std::fill(target.last_seen.begin(), target.last_seen.end(), missing_point());
    target.has_box = false;
  }
  if (!new_labels.empty() || labels_not_listed > 0) observer_.on_unknown_labels(index, new_labels, labels_not_listed);
  if (target.matched_once && followed == target.followed) return;
  target.matched_once = true;
  target.present = present;
  target.followed = std::move(followed);

  const size_t markers = target.config.marker_names.size();
  const auto labelled = static_cast<size_t>(markers - static_cast<size_t>(std::count(taken_by.begin(), taken_by.end(), 0)));
  std::string detail;
  if (present) {
    detail = "follows " + quoted(target.followed) + ": " + std::to_string(labelled) + " of the subject's " +
             std::to_string(markers) + " markers labelled";
    if (shared_labels)
      detail += "; labels carried by several subjects are taken from the first (name the one to follow: --subject NAME=FILE)";
  } else if (!target.config.name.empty()) {
    detail = "the stream has no subject \"" + target.config.name + "\" (it has " + quoted(subjects) + ")";
  } else {
    detail = "no subject in the stream carries any of the subject's " + std::to_string(markers) + " marker labels (it has " +
             quoted(subjects) + ")";
  }
  observer_.on_match(index, present, detail);
}

void SubjectRouter::fill_labelled(Target& target, const SourceFrame& frame, MarkerFrame& out) {
  out.clear();
  out.frame_number = frame.frame_number;
  out.source_time_ns = frame.source_time_ns;
  out.receive_time_ns = frame.receive_time_ns;
  out.capture_latency_ns = frame.capture_latency_ns;
  out.source_rate_hz = frame.rate_hz;
  out.timecode = frame.timecode;
  for (size_t k = 0; k < target.slots.size(); ++k) {
    const Slot& slot = target.slots[k];
    // Bounds checked: a source whose positions do not match its labels loses those, not memory.
    if (slot.subject >= frame.labelled.size() || slot.label >= frame.labelled[slot.subject].size()) continue;
    const Vec3& p = frame.labelled[slot.subject][slot.label];
    if (!plausible(p)) {
      if (is_present(p)) ++out.implausible_points;
      else if (!p.array().isNaN().all()) ++out.rejected_points;  // NaN is "occluded"; anything else is broken
      continue;
    }
    if (slot.marker == kUnknownLabel) {
      ++out.unknown_labels;
      add_unlabelled(out, p, kUnknownLabelIds - static_cast<int>(k));
      continue;
    }
    const auto m = static_cast<size_t>(slot.marker);
    if (m >= out.labelled.size()) continue;
    out.labelled[m] = p;
    target.last_seen[m] = p;
  }
  target.has_box = false;
  for (const Vec3& p : target.last_seen) {
    if (!is_present(p)) continue;
    target.box_min = target.has_box ? target.box_min.cwiseMin(p) : p;
    target.box_max = target.has_box ? target.box_max.cwiseMax(p) : p;
    target.has_box = true;
  }
}

double SubjectRouter::distance_to(const Target& target, const Vec3& p, double below) const {
  if (!target.has_box || box_distance(p, target.box_min, target.box_max) >= below) return below;
  double best_squared = below * below;
  for (const Vec3& q : target.last_seen)
    if (is_present(q)) best_squared = std::min(best_squared, (q - p).squaredNorm());
  return std::sqrt(best_squared);
}

void SubjectRouter::give_unlabelled(const SourceFrame& frame, std::span<MarkerFrame* const> out, Stats& stats) {
  candidates_.clear();
  for (size_t t = 0; t < targets_.size(); ++t)
    if (targets_[t].present && out[t]) candidates_.push_back(static_cast<int>(t));
  const bool has_ids = frame.unlabelled_ids.size() == frame.unlabelled.size();
  for (size_t i = 0; i < frame.unlabelled.size(); ++i) {
    const Vec3& p = frame.unlabelled[i];
    if (!plausible(p)) {
      ++(is_present(p) ? stats.implausible_points : stats.rejected_points);
      continue;
    }
    int owner = candidates_.size() == 1 ? candidates_.front() : -1;
    if (candidates_.size() > 1) {
      double nearest = std::numeric_limits<double>::infinity();
      for (int t : candidates_) {
        const double d = distance_to(targets_[static_cast<size_t>(t)], p, nearest);
        if (d < nearest) {
          nearest = d;
          owner = t;
        }
      }
    }
    if (owner < 0) {
      ++stats.unassigned_points;
      continue;
    }
    add_unlabelled(*out[static_cast<size_t>(owner)], p, has_ids ? frame.unlabelled_ids[i] : -1);
  }
}

SubjectRouter::Stats SubjectRouter::route(const SourceFrame& frame, std::span<MarkerFrame* const> out) {
  Stats stats;
  if (out.size() != targets_.size()) return stats;
  if (!matched_ || frame.structure_version != structure_version_) rematch(frame);
  for (size_t t = 0; t < targets_.size(); ++t)
    if (targets_[t].present && out[t]) fill_labelled(targets_[t], frame, *out[t]);
  give_unlabelled(frame, out, stats);
  return stats;
}

}  // namespace skinstream::server
