#pragma once
// Matches a capture system's frame (SourceFrame) to our subjects, the same way for every source:
// first which source subject each of our subjects follows, then, within that source subject
// only, which label is which of its markers. The actors on a stage wear one marker template, so
// a label means something only within its subject: Actor2's "LFHD" never reaches Actor1.
//
// A subject named after a source subject (`--subject Actor1=actor1.sksubj`) follows the source
// subject of that name and no other. An unnamed subject (a plain `--subject FILE`, one actor)
// follows every source subject that carries at least one of its labels (several source subjects
// may split one body); a label that two of them carry is taken from the first, and the match
// says so. Labels of a followed subject that the subject file lacks become that subject's
// unlabelled points; source subjects nobody follows are ignored (another performer).
//
// The source's unlabelled points: with one of our subjects present, all of them are its; with
// several, each point goes to the subject with a marker nearest to it (the markers' latest
// measured positions), so no point is given to two subjects in one frame.
//
// Every position is checked before it goes anywhere, the same for every source: one that is not
// finite, or farther from the capture system's origin than max_coordinate_mm along any axis (no
// stage is that large: a source sending 3.4e38 mm or 1e36 m once made the daemon publish
// infinite parameters, and 1e7 mm put vertices 612 m away), is taken as missing and counted
// (MarkerFrame::rejected_points and implausible_points, Stats). NaN alone is "occluded".
//
// The matching is redone only when the source's structure_version changes (and allocates then);
// otherwise route() allocates nothing. What it reports about names is bounded: each unknown
// source subject name and each unknown label is reported once, at most kMaxRememberedNames of
// each are remembered, and beyond that they are only counted (a source inventing new names every
// frame grows neither the memory nor the log).

#include <cstddef>
#include <span>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "server/ingest/bounded_name_set.h"
#include "server/ingest/marker_frame.h"
#include "server/ingest/source_frame.h"

namespace skinstream::server {

// One of our subjects, as the router sees it.
struct SubjectTarget {
  std::string name;  // the source subject it follows; empty: every one carrying its labels
  std::vector<std::string> marker_names;
};

class SubjectRouter {
 public:
  static constexpr size_t kMaxRememberedNames = 256;
  // Trajectory id of an unknown label's point: this minus the label's place in the subject's
  // labels (clear of the filler's own ids, -marker - 1, and of the source's, >= 0).
  static constexpr int kUnknownLabelIds = -(1 << 30);

  // Called on the routing thread (the daemon's io thread); must not block.
  class Observer {
   public:
    virtual ~Observer() = default;
    // At the first frame and whenever what `target` follows changes: whether it is in the
    // stream, and a sentence saying what it follows or why it is absent.
    virtual void on_match(int target, bool present, std::string_view detail) = 0;
    // Source subjects none of ours follows, first seen at this change of the stream's subjects:
    // their names (while fewer than kMaxRememberedNames are remembered) and how many more there
    // were that are not remembered.
    virtual void on_unknown_subjects(std::span<const std::string> names, size_t not_listed) = 0;
    // Labels of a followed source subject that `target`'s subject file does not have (they are
    // used as unlabelled points), first seen; as above.
    virtual void on_unknown_labels(int target, std::span<const std::string> names, size_t not_listed) = 0;
  };

  struct Stats {
    int unassigned_points = 0;    // unlabelled points near none of the present subjects' markers
    int rejected_points = 0;      // unlabelled points that were not finite
    int implausible_points = 0;   // unlabelled points outside the capture volume
  };

  // No coordinate farther than this from the origin, by default (mm): 50 m.
  static constexpr double kDefaultMaxCoordinateMm = 50'000.0;

  SubjectRouter(std::vector<SubjectTarget> targets, Observer& observer, double max_coordinate_mm = kDefaultMaxCoordinateMm);

  int target_count() const { return static_cast<int>(targets_.size()); }
  const SubjectTarget& target(int t) const { return targets_[static_cast<size_t>(t)].config; }

  // Fills *out[t] for every target present in `frame` (out has target_count() entries, each
  // sized for its target's markers, or null to leave that target out). present(t) says which
  // were filled. Returns the frame's counts of unlabelled points that went to nobody.
  Stats route(const SourceFrame& frame, std::span<MarkerFrame* const> out);
  bool present(int t) const { return targets_[static_cast<size_t>(t)].present; }

  // The routing thread, between two frames: target t is another subject model (a swap: its
  // markers may differ). Matched afresh at the next frame, which says so to the Observer.
  void replace_target(int t, SubjectTarget target);
  // The routing thread, between two frames: a subject added at the end (index target_count()),
  // or target t removed (the later ones move down one). Matched afresh at the next frame.
  void add_target(SubjectTarget target);
  void remove_target(int t);

  // How many of target t's markers `subject` labels (a check before a replay starts).
  int markers_labelled_by(int t, const SourceSubject& subject) const;

  size_t remembered_subject_names() const { return unknown_subjects_.size(); }
  size_t remembered_label_names(int t) const { return targets_[static_cast<size_t>(t)].unknown_labels.size(); }

 private:
  static constexpr int kUnknownLabel = -1;  // a slot's marker: becomes an unlabelled point
  struct Slot {
    size_t subject = 0, label = 0;  // in the SourceFrame
    int marker = kUnknownLabel;     // in the target's marker order
  };
  struct Target {
    explicit Target(SubjectTarget c);
    SubjectTarget config;
    std::unordered_map<std::string, int> marker_index;
    std::vector<Slot> slots;
    std::vector<std::string> followed;  // names of the source subjects followed now
    bool present = false;
    bool matched_once = false;
    BoundedNameSet unknown_labels{kMaxRememberedNames};
    // For the unlabelled points: each marker's latest measured position, and their box.
    std::vector<Vec3> last_seen;
    Vec3 box_min = Vec3::Zero(), box_max = Vec3::Zero();
    bool has_box = false;
  };

  void rematch(const SourceFrame& frame);
  void match(Target& target, int index, const std::vector<SourceSubject>& subjects, std::vector<char>& followed_by_any);
  void fill_labelled(Target& target, const SourceFrame& frame, MarkerFrame& out);
  void give_unlabelled(const SourceFrame& frame, std::span<MarkerFrame* const> out, Stats& stats);
  double distance_to(const Target& target, const Vec3& p, double below) const;

  // Finite and within the capture volume.
  bool plausible(const Vec3& p) const { return is_present(p) && p.cwiseAbs().maxCoeff() <= max_coordinate_mm_; }

  std::vector<Target> targets_;
  Observer& observer_;
  double max_coordinate_mm_;
  bool matched_ = false;
  uint64_t structure_version_ = 0;
  BoundedNameSet unknown_subjects_{kMaxRememberedNames};
  std::vector<int> candidates_;  // targets that may take unlabelled points this frame
};

}  // namespace skinstream::server
