#include "core/gap_filler.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/rigid_fit_leverage.h"

namespace skinstream {

GapFiller::GapFiller(const SubjectModel& model, const GapFillerOptions& options)
    : model_(model),
      options_(options),
      n_(model.marker_count()),
      tracks_(model.marker_count()),
      label_check_(model),
      carry_(model, options.rate_hz),
      single_gaps_(model),
      ring_calibration_(model, options.rate_hz),
      region_statistics_(model, RegionLearningOptions{.rate_hz = options.rate_hz}) {
  // Reverse one-rings: which markers' PCA models can predict marker i, and at which slot.
  std::vector<std::vector<std::pair<int, int>>> predictors(n_);
  for (int j = 0; j < n_; ++j)
    for (int k = model.ring_offsets[j]; k < model.ring_offsets[j + 1]; ++k)
      predictors[model.ring[k]].push_back({j, k - model.ring_offsets[j]});
  predictor_offsets_.push_back(0);
  for (int i = 0; i < n_; ++i) {
    for (const auto& [j, slot] : predictors[i]) {
      predictor_marker_.push_back(j);
      predictor_slot_.push_back(slot);
    }
    predictor_offsets_.push_back(static_cast<int>(predictor_marker_.size()));
    eps1_.push_back(model.parameters.alpha1 * model.neighbour_distance(i));
    eps2_.push_back(model.parameters.alpha2 * model.neighbour_distance(i));
  }

  assigned_id_.assign(n_, kNoFragment);
  probation_start_.assign(n_, -1);
  refused_id_.assign(n_, kNoFragment);
  revoked_.assign(n_, 0);
  gap_offset_.assign(n_, Vec3::Zero());
  current_.assign(n_, Vec3::Zero());
  status_.assign(n_, MarkerStatus::Held);
  observed_.assign(n_, 0);
  estimated_.assign(n_, 0);
  has_rotation_.assign(n_, 0);
  changed_.reserve(n_);
  estimate_.assign(n_, Vec3::Zero());
  rotation_.assign(n_, Eigen::Matrix3d::Identity());
  available_neighbours_.assign(n_, 0);
  missing_.reserve(n_);
  rigid_queue_.reserve(n_ + predictor_marker_.size());  // every marker once, then once per count raised
  free_points_.assign(kMaxFreePoints, Vec3::Zero());
  free_ids_.assign(kMaxFreePoints, 0);
  free_used_.assign(kMaxFreePoints, 0);
  candidates_.reserve(n_);
  pca_stamp_.assign(n_, -1);
  pca_ok_.assign(n_, 0);
  pca_novelty_.assign(n_, 1.0);
  pca_rotation_.assign(n_, Eigen::Matrix3d::Identity());
  pca_slot_local_.assign(model.ring.size(), Vec3::Zero());
  pca_slot_variance_.assign(model.ring.size(), 1.0);
  rigid_support_.assign(n_, 0);
  rigid_novelty_.assign(n_, 1.0);
  rigid_variance_.assign(n_, 0.0);
  leverage_.assign(model.ring.size(), 0.0);
  leverage_mask_.assign(n_, 0);
  // Each marker's training error of eq. 2 with its whole ring seen, read as the ring members'
  // departure from rigid seen through their leverage on the fit.
  for (int i = 0; i < n_; ++i) {
    const int first = model.ring_offsets[i], ring = model.ring_size(i);
    double leverage = 0.0;
    if (ring > 0) {
      rigid_fit_leverage({&model.ring_local_reference[first], static_cast<size_t>(ring)}, {&leverage_[first], static_cast<size_t>(ring)});
      leverage_mask_[i] = (1u << ring) - 1u;
      for (int k = 0; k < ring; ++k) leverage += leverage_[first + k];
    }
    rigid_member_variance_.push_back(leverage > 0.0 ? model.pca[i].rigid_variance / leverage : model.pca[i].rigid_variance);
  }
  static_assert(SubjectModel::kMaxRing < 32, "observed slots are a 32-bit mask");
  for (int j = 0; j < n_; ++j) {
    pattern_offset_.push_back(static_cast<int>(pattern_factor_.size()));
    pattern_factor_.resize(pattern_factor_.size() + model.pca[j].variance.size() * model.pca[j].variance.size());
  }
  pattern_mask_.assign(n_, 0);  // no pattern: a mask has at least two bits
  const size_t scratch = std::max<size_t>(n_, SubjectModel::kMaxRing);
  scratch_source_.assign(scratch, Vec3::Zero());
  scratch_target_.assign(scratch, Vec3::Zero());
  scratch_index_.assign(scratch, 0);
  region_positions_.assign(SubjectModel::kMaxRing, Vec3::Zero());
  region_observed_.assign(SubjectModel::kMaxRing, 0);
  region_solves_.resize(model.has_regions() ? n_ : 0);
}

void GapFiller::reset() {
  tracks_.reset();
  std::fill(assigned_id_.begin(), assigned_id_.end(), kNoFragment);
  std::fill(probation_start_.begin(), probation_start_.end(), -1);
  std::fill(refused_id_.begin(), refused_id_.end(), kNoFragment);
  std::fill(gap_offset_.begin(), gap_offset_.end(), Vec3::Zero());
  carry_.reset();
  region_statistics_.reset();
  ring_calibration_.reset();
  for (RegionSolve& solve : region_solves_) solve.observed_mask = 0;
}

void GapFiller::add_free_point(const Vec3& p, int id) {
  if (!is_present(p) || free_count_ >= kMaxFreePoints) {
    ++stats_.ignored_points;
    return;
  }
  free_points_[free_count_] = p;
  free_ids_[free_count_] = id;
  free_used_[free_count_] = 0;
  ++free_count_;
}

FillStats GapFiller::run(const FrameInput& in, const FrameOutput& out) {
  stats_ = FillStats{};
  if (static_cast<int>(in.labelled.size()) != n_ || static_cast<int>(out.positions.size()) != n_ ||
      static_cast<int>(out.status.size()) != n_ || (!out.fragments.empty() && static_cast<int>(out.fragments.size()) != n_) ||
      (!out.revoked.empty() && static_cast<int>(out.revoked.size()) != n_) ||
      (!in.unlabelled_ids.empty() && in.unlabelled_ids.size() != in.unlabelled.size())) {
    stats_.ok = false;
    return stats_;
  }
  ++frame_;
  ++solve_stamp_;
  free_count_ = 0;
  for (int i = 0; i < n_; ++i) {
    current_[i] = in.labelled[i];
    observed_[i] = is_present(current_[i]);
    status_[i] = MarkerStatus::Measured;
    has_rotation_[i] = 0;
    if (!observed_[i] && (std::isfinite(current_[i].x()) || std::isfinite(current_[i].y()) || std::isfinite(current_[i].z())))
      ++stats_.ignored_points;  // partly NaN: a broken sample, treated as missing
  }
  // Free-point ids: the source's trajectory ids (>= 0); rejected labelled points get -(i + 1).
  for (size_t p = 0; p < in.unlabelled.size(); ++p)
    add_free_point(in.unlabelled[p], in.unlabelled_ids.empty() ? static_cast<int>(p) : in.unlabelled_ids[p]);

  label_check_.clear();
  if (options_.check_labels && tracks_.has_last())
    label_check_.find_suspects(current_, observed_, eps2_, tracks_);
  estimate_rigid();
  if (!label_check_.suspects().empty()) judge_suspect_labels();
  std::fill(revoked_.begin(), revoked_.end(), 0);
  for (int i = 0; i < n_; ++i)
    if (observed_[i]) {  // the capture system has it again
      assigned_id_[i] = kNoFragment;
      probation_start_[i] = -1;
      refused_id_[i] = kNoFragment;
    }

  relabel();
  fill_missing();
  if (options_.carry_from_gap_start) carry_.check(frame_, current_, observed_);

  for (int i = 0; i < n_; ++i) {
    out.positions[i] = current_[i];
    out.status[i] = status_[i];
    if (!out.fragments.empty()) out.fragments[i] = status_[i] == MarkerStatus::Relabelled ? assigned_id_[i] : kNoFragment;
    if (!out.revoked.empty()) out.revoked[i] = revoked_[i];
    if (is_present(in.labelled[i]) && current_[i] != in.labelled[i]) ++stats_.changed_measured;
    switch (status_[i]) {
      case MarkerStatus::Measured: ++stats_.measured; break;
      case MarkerStatus::Relabelled: ++stats_.relabelled; break;
      case MarkerStatus::FilledPca:
      case MarkerStatus::FilledRigid: ++stats_.filled; break;
      case MarkerStatus::Held: ++stats_.held; break;
    }
  }
  tracks_.advance(current_, status_);
  if (options_.use_regions && options_.learn_regions) region_statistics_.learn(current_, status_);
  if (options_.calibrate_rings) ring_calibration_.check(current_, status_, single_gaps_);
  return stats_;
}

// The suspects (label_check.h) judged one by one, each against the estimates of the others as
// they stand: one kept is measured again for the next one's judgement; one rejected becomes a free
// point for the relabelling. The estimates are then redone with the points kept.
void GapFiller::judge_suspect_labels() {
  const FrameEstimates frame = frame_estimates();
  for (int i : label_check_.suspects()) {
    if (label_check_.rejects(i, frame, eps2_, *this)) {
      add_free_point(current_[i], -(i + 1));
      ++stats_.rejected_labels;
    } else {
      observed_[i] = 1;
      changed_.push_back(i);
    }
  }
  refresh_estimates();
}

FrameEstimates GapFiller::frame_estimates() const {
  return {current_, observed_, missing_, estimated_, estimate_, eps1_, tracks_};
}

// Eq. 2, greedy: repeatedly estimate the missing marker with the most available neighbours
// (at least three), then count it as available for the others.
void GapFiller::estimate_rigid() {
  missing_.clear();
  for (int i = 0; i < n_; ++i) {
    estimated_[i] = observed_[i];
    if (observed_[i]) estimate_[i] = current_[i];
    else missing_.push_back(i);
  }
  for (int i : missing_) {
    int count = 0;
    for (int k = model_.ring_offsets[i]; k < model_.ring_offsets[i + 1]; ++k) count += estimated_[model_.ring[k]];
    available_neighbours_[i] = count;
  }
  // The marker with the most available neighbours first, the lowest index among equals: a heap
  // of (count, marker) entries, a stale one (its marker since estimated, or counted higher) skipped.
  auto before = [](const RigidQueueEntry& a, const RigidQueueEntry& b) {
    return a.count != b.count ? a.count < b.count : a.marker > b.marker;
  };
  rigid_queue_.clear();
  for (int i : missing_)
    if (available_neighbours_[i] >= kRigidSupport) rigid_queue_.push_back({available_neighbours_[i], i});
  std::make_heap(rigid_queue_.begin(), rigid_queue_.end(), before);
  while (!rigid_queue_.empty()) {
    std::pop_heap(rigid_queue_.begin(), rigid_queue_.end(), before);
    const RigidQueueEntry next = rigid_queue_.back();
    rigid_queue_.pop_back();
    if (estimated_[next.marker] || available_neighbours_[next.marker] != next.count) continue;
    fit_rigid_estimate(next.marker);
    for (int p = predictor_offsets_[next.marker]; p < predictor_offsets_[next.marker + 1]; ++p) {
      const int j = predictor_marker_[p];
      if (estimated_[j] || ++available_neighbours_[j] < kRigidSupport) continue;
      rigid_queue_.push_back({available_neighbours_[j], j});
      std::push_heap(rigid_queue_.begin(), rigid_queue_.end(), before);
    }
  }
}

// Eq. 2 for marker i from the ring members known (observed or estimated) now, at least three
// (estimate_rigid picks only such a marker).
void GapFiller::fit_rigid_estimate(int i) {
  const int first = model_.ring_offsets[i];
  int count = 0, observed_support = 0;
  uint32_t mask = 0;
  for (int k = first; k < model_.ring_offsets[i + 1]; ++k) {
    const int j = model_.ring[k];
    observed_support += observed_[j];
    if (!estimated_[j]) continue;
    scratch_source_[count] = model_.ring_local_reference[k];
    scratch_target_[count] = estimate_[j];
    scratch_index_[count] = j;
    mask |= 1u << (k - first);
    ++count;
  }
  rigid_support_[i] = observed_support;
  RigidTransform t;
  fit_rigid({scratch_source_.data(), static_cast<size_t>(count)}, {scratch_target_.data(), static_cast<size_t>(count)}, t);
  // Its variance: every member's departure from rigid, and for a member that was itself only
  // estimated that estimate's variance too, each seen through its leverage on this fit (few
  // members, or far or nearly collinear ones, make a poor fit; an error in a member the chain
  // estimated is carried on).
  const std::span<double> leverage(&leverage_[first], static_cast<size_t>(count));
  if (leverage_mask_[i] != mask) {
    rigid_fit_leverage({scratch_source_.data(), static_cast<size_t>(count)}, leverage);
    leverage_mask_[i] = mask;
  }
  double variance = 0.0, member_variances = 0.0, miss = 0.0;
  for (int k = 0; k < count; ++k) {
    const int j = scratch_index_[k];
    const double member = rigid_member_variance_[i] * ring_calibration_.rigid(i) +
                          (observed_[j] ? 0.0 : rigid_estimate_variance(j, true));
    variance += leverage[k] * member;
    member_variances += member;
    miss += (t.apply(scratch_source_[k]) - scratch_target_[k]).squaredNorm();
  }
  rigid_variance_[i] = std::max(variance, model_.pca[i].rigid_variance * ring_calibration_.rigid(i));
  // A ring that no longer moves rigidly (a joint bent beyond training) makes the estimate worth
  // less: its members' miss against the fit, over what those variances lead one to expect of
  // it. The fit takes six of the 3n coordinates: three members leave only their three
  // distances to test.
  rigid_novelty_[i] = misfit_ratio(miss, (3.0 * count - 6.0) / count * member_variances);
  estimate_[i] = t.translation;  // the local frame's origin is the marker
  rotation_[i] = t.rotation;
  has_rotation_[i] = 1;
  estimated_[i] = 1;
}

void GapFiller::relabel() {
  // Fragments already standing for a marker stay while within eps2 of where it is expected; one
  // still on probation (taken less than confirm_frames ago) only while it passes the taking test.
  for (int i : missing_) {
    const int id = assigned_id_[i];
    if (refused_id_[i] != kNoFragment && find_free_point(refused_id_[i]) < 0) refused_id_[i] = kNoFragment;
    if (id == kNoFragment) continue;
    const int found = find_free_point(id);
    Vec3 expected;
    if (found >= 0 && !expected_position(i, expected)) expected = tracks_.last(i);  // no estimate: continuity
    const double distance = found >= 0 ? (free_points_[found] - expected).norm() : 0.0;
    const bool on_probation = probation_start_[i] >= 0;
    const bool keep = found >= 0 && (on_probation ? ambiguity_free_match(i, found, distance) : distance <= eps2_[i]);
    if (keep) {
      take_free_point(i, found);
      if (on_probation && frame_ - probation_start_[i] >= options_.confirm_frames) probation_start_[i] = -1;
      continue;
    }
    // Not confirmed (a fragment that merely ends says nothing against it): the frames since it
    // was taken are given back as estimates, and the fragment is not taken for this marker again.
    if (on_probation && found >= 0) {
      revoked_[i] = static_cast<int>(frame_ - probation_start_[i]);
      refused_id_[i] = id;
      probation_start_[i] = -1;
      tracks_.take_last_as_estimated(i);  // still in its gap: no continuity from the fragment
    }
    assigned_id_[i] = kNoFragment;
  }
  refresh_estimates();
  // New matches: each still-missing marker's nearest free point within eps1 of where it is
  // expected, closest pairs first. Points taken at the edge of an occluded patch make the
  // estimates inside it better, so matching repeats while it finds something.
  for (int round = 0; round < kRelabelRounds; ++round) {
    candidates_.clear();
    for (int i : missing_) {
      // Most missing markers are occluded with no free point anywhere near: skip those before
      // paying for the PCA estimate (a free point within eps1 of it is within a few eps1 of
      // the rigid estimate, whose errors are a fraction of eps1).
      if (observed_[i] || !estimated_[i] || !free_point_near(estimate_[i], kPrefilterReach * eps1_[i])) continue;
      Vec3 expected;
      if (!expected_position(i, expected)) continue;
      int best = -1;
      double best_distance = eps1_[i];
      for (int p = 0; p < free_count_; ++p) {
        if (free_used_[p] || free_ids_[p] == refused_id_[i]) continue;
        const double d = (free_points_[p] - expected).norm();
        if (d <= best_distance) {
          best = p;
          best_distance = d;
        }
      }
      if (best >= 0 && ambiguity_free_match(i, best, best_distance)) candidates_.push_back({best_distance, i, best});
    }
    if (candidates_.empty()) break;
    std::sort(candidates_.begin(), candidates_.end(),
              [](const Candidate& a, const Candidate& b) { return a.distance < b.distance; });
    for (const Candidate& c : candidates_) {
      if (free_used_[c.point] || observed_[c.marker]) continue;
      take_free_point(c.marker, c.point);
      assigned_id_[c.marker] = free_ids_[c.point];
      if (options_.confirm_frames > 0) probation_start_[c.marker] = frame_;
    }
    refresh_estimates();
  }
}

// Eq. 3's test for free point p at `distance` from where marker i is expected: within eps1, and
// no other missing marker expected nearly as close (within twice the distance), by its estimate
// or, where it has none (its whole neighbourhood gone), by its own track. Where two markers both
// reach a point (skin touching skin, neighbours close together) it is taken for neither until
// the motion tells them apart.
bool GapFiller::ambiguity_free_match(int i, int p, double distance) {
  if (distance > eps1_[i]) return false;
  if (free_ids_[p] == -(i + 1)) return true;  // its own labelled point, held back by the label check
  const FrameEstimates frame = frame_estimates();
  return nearest_other_expected(frame, *this, i, free_points_[p]) >= 2.0 * distance &&
         nearest_other_on_track(frame, *this, i, free_points_[p]) >= 2.0 * distance;
}

int GapFiller::find_free_point(int id) const {
  for (int p = 0; p < free_count_; ++p)
    if (!free_used_[p] && free_ids_[p] == id) return p;
  return -1;
}

bool GapFiller::free_point_near(const Vec3& p, double reach) const {
  const double reach_squared = reach * reach;
  for (int k = 0; k < free_count_; ++k)
    if (!free_used_[k] && (free_points_[k] - p).squaredNorm() <= reach_squared) return true;
  return false;
}

void GapFiller::take_free_point(int marker, int point) {
  changed_.push_back(marker);
  free_used_[point] = 1;
  current_[marker] = free_points_[point];
  observed_[marker] = 1;
  status_[marker] = MarkerStatus::Relabelled;
}

// After points were taken for the markers in changed_: rigid estimates again from the new set
// (their chains reach past the ring), and the PCA solves that use those markers redone on
// demand. A model's solve depends only on its ring's observed members, so the others stand.
void GapFiller::refresh_estimates() {
  if (changed_.empty()) return;
  estimate_rigid();
  for (int m : changed_) {
    pca_stamp_[m] = -1;
    for (int p = predictor_offsets_[m]; p < predictor_offsets_[m + 1]; ++p) pca_stamp_[predictor_marker_[p]] = -1;
  }
  changed_.clear();
}

// Section 4.3 for the model of marker j: rotate j's observed one-ring into its local frame
// (eq. 5), fit the PCA coefficients to it (pca_fit.h) and keep, for every ring member that is
// not observed, its reconstruction and calibrated predictive variance.
bool GapFiller::solve_pca(int j) {
  pca_stamp_[j] = solve_stamp_;
  pca_ok_[j] = 0;
  const MarkerPcaModel& m = model_.pca[j];
  const int first = model_.ring_offsets[j];
  const int ring = model_.ring_size(j);
  int count = 0;
  for (int k = 0; k < ring; ++k) {
    const int member = model_.ring[first + k];
    if (!observed_[member]) continue;
    scratch_source_[count] = current_[member] - current_[j];
    scratch_target_[count] = model_.ring_local_reference[first + k];
    scratch_index_[count] = k;
    ++count;
  }
  if (count < 2) return false;
  Eigen::Matrix3d& r = pca_rotation_[j];
  fit_rotation({scratch_source_.data(), static_cast<size_t>(count)}, {scratch_target_.data(), static_cast<size_t>(count)}, r);
  for (int o = 0; o < count; ++o) scratch_source_[o] = r * scratch_source_[o];
  if (count == ring - 1) {
    // The common case, one member missing: the precomputed linear map of that pattern.
    int missing_slot = 0;
    while (observed_[model_.ring[first + missing_slot]]) ++missing_slot;
    const int at = first + missing_slot;
    const double miss =
        single_gaps_.reconstruct(j, missing_slot, {scratch_source_.data(), static_cast<size_t>(count)},
                                 {scratch_index_.data(), static_cast<size_t>(count)}, pca_slot_local_[at]);
    pca_slot_variance_[at] = single_gaps_.variance(at) * ring_calibration_.ring(at);
    pca_novelty_[j] = novelty_factor(miss, count, m.residual_variance);
    pca_ok_[j] = 1;
    return true;
  }
  // Several missing: the pattern's factor, made when the pattern changes.
  const std::span<const int> slots(scratch_index_.data(), static_cast<size_t>(count));
  const size_t components = m.variance.size();
  const std::span<double> factor(pattern_factor_.data() + pattern_offset_[j], components * components);
  uint32_t mask = 0;
  for (int slot : slots) mask |= 1u << slot;
  if (pattern_mask_[j] != mask) {
    pattern_mask_[j] = 0;
    if (!PcaFit::factor_slots(m, slots, factor)) return false;
    pattern_mask_[j] = mask;
  }
  const std::span<const Vec3> local(scratch_source_.data(), static_cast<size_t>(count));
  pca_fit_.fit_factored(m, slots, local, factor);
  pca_novelty_[j] = novelty_factor(pca_fit_.squared_miss(m, slots, local), count, m.residual_variance);
  for (int k = 0; k < ring; ++k) {
    if (observed_[model_.ring[first + k]]) continue;
    pca_slot_local_[first + k] = pca_fit_.reconstruct(m, k);
    // With several members missing the exact predictive variance costs a triangular solve per
    // member; the single-gap variance, grown by the share of the ring that is missing, ranks
    // the estimates almost the same at a fraction of the cost.
    pca_slot_variance_[first + k] =
        single_gaps_.variance(first + k) * ring_calibration_.ring(first + k) * (ring - 1) / count;
  }
  pca_ok_[j] = 1;
  return true;
}

// Moves `previous` (where a marker was last frame) with the rigid motion of `members` from the
// last frame to this one. Needs three members seen in both frames: a member that went missing
// with the marker has only an estimate now, and a poor one would move the marker by its error
// (seen: a shin marker sent 143 mm off at the first frame of a gap it shared with the ankle).
bool GapFiller::transfer_motion(int first, int last, const std::vector<int>& members, const Vec3& previous, Vec3& out) {
  int count = 0;
  for (int k = first; k < last; ++k) {
    const int j = members[k];
    if (!observed_[j] || !is_observed(tracks_.last_status(j))) continue;
    scratch_source_[count] = tracks_.last(j);
    scratch_target_[count] = estimate_[j];
    ++count;
  }
  if (count < 3) return false;
  RigidTransform t;
  fit_rigid({scratch_source_.data(), static_cast<size_t>(count)}, {scratch_target_.data(), static_cast<size_t>(count)}, t);
  out = t.apply(previous);
  return true;
}

// The neighbours' PCA estimates of marker i, each weighted by its calibrated predictive
// variance, fused with the rigid estimate weighed likewise; with `misfit`, each variance grown by
// its model's novelty this frame. Returns how many PCA models spoke.
int GapFiller::pca_estimate(int i, Vec3& out, double* out_variance, bool misfit) {
  Vec3 sum = Vec3::Zero();
  double weights = 0.0, precision = 0.0;
  int count = 0, opinions = 0;
  for (int p = predictor_offsets_[i]; p < predictor_offsets_[i + 1]; ++p) {
    const int j = predictor_marker_[p];
    if (!observed_[j]) continue;
    if (pca_stamp_[j] != solve_stamp_) solve_pca(j);
    if (!pca_ok_[j]) continue;
    const int at = model_.ring_offsets[j] + predictor_slot_[p];
    const double variance = pca_slot_variance_[at] * (misfit ? pca_novelty_[j] : 1.0);
    const double weight = options_.weight_by_variance ? 1.0 / variance : 1.0;
    sum += weight * (current_[j] + pca_rotation_[j].transpose() * pca_slot_local_[at]);
    weights += weight;
    precision += 1.0 / variance;
    ++opinions;
    ++count;
  }
  // The rigid estimate joins as one more opinion, weighed by its error on the training take,
  // inflated when part of the ring it stood on was itself only estimated.
  if (count > 0 && options_.weight_by_variance && options_.fuse_rigid && estimated_[i] && rigid_support_[i] > 0) {
    const double variance = rigid_estimate_variance(i, misfit);
    sum += estimate_[i] / variance;
    weights += 1.0 / variance;
    precision += 1.0 / variance;
    ++opinions;
  }
  if (count > 0) out = sum / weights;
  // The opinions rest on the same observed markers, so together they are no surer than a typical
  // one: the harmonic mean of their variances, not the variance of independent ones' mean.
  if (count > 0 && out_variance) *out_variance = opinions / precision;
  return count;
}

// Where the relabeller expects a missing marker: its best estimate from the neighbours alone.
// Not the continuity offset: that comes from the marker's own past, and a fragment drifting
// away would drag it along and be taken back. Nor the novelty: a ring that misfits while points
// are being taken is as often a point taken wrongly as a new pose (with it, 0.37% of the
// synthetic punch's fragments were labelled wrongly, 0.28% without). False when there is no
// estimate.
bool GapFiller::expected_position(int i, Vec3& out, double* out_variance) {
  if (options_.use_pca && pca_estimate(i, out, out_variance) > 0) return true;
  if (!estimated_[i]) return false;
  out = estimate_[i];
  if (out_variance) *out_variance = rigid_estimate_variance(i);
  return true;
}

double GapFiller::rigid_estimate_variance(int i, bool misfit) const {
  return rigid_variance_[i] * (misfit ? rigid_novelty_[i] : 1.0);
}

// Marker i's regional PCA opinion from the observed members of its region (region_pca_fit.h).
// Not asked for when the other opinions' variance is so much smaller than the least the region
// can claim (its residual, calibrated) that it would weigh under 5%: the common case of a short
// gap in a well seen neighbourhood, where it would cost the frame time and change nothing.
bool GapFiller::region_estimate(int i, double other_variance, Vec3& out, double& out_variance) {
  if (!options_.use_regions || !options_.use_pca || !options_.weight_by_variance || !model_.has_regions()) return false;
  constexpr double kNegligibleShare = 0.05;
  const MarkerPcaModel& region = model_.region_pca[i];
  if (region.training_frames == 0 ||
      other_variance < kNegligibleShare * region.residual_variance * region_statistics_.calibration(i))
    return false;
  const int first = model_.region_offsets[i], size = model_.region_offsets[i + 1] - first;
  for (int k = 0; k < size; ++k) {
    const int member = model_.region[first + k];
    region_positions_[k] = current_[member];
    region_observed_[k] = observed_[member];
  }
  RegionSolve& solve = region_solves_[i];
  const uint32_t mask = region_observed_mask({region_observed_.data(), static_cast<size_t>(size)});
  const long version = region_statistics_.version(i);
  if (!solve.matches(mask, version) && !prepare_region_solve(region_statistics_.blended(i), mask, version, solve)) return false;
  region_fit_.estimate(solve, {region_positions_.data(), static_cast<size_t>(size)}, out, out_variance);
  return true;
}

void GapFiller::fill_missing() {
  const double decay_frames = options_.continuity_seconds * options_.rate_hz;
  const bool carry_on = options_.carry_from_gap_start && options_.weight_by_variance;
  // Two estimates of one point weighed by their variances.
  auto combine = [](const Vec3& a, double variance_a, const Vec3& b, double variance_b) {
    return (a * variance_b + b * variance_a) / (variance_a + variance_b);
  };
  auto combined_variance = [](double variance_a, double variance_b) { return variance_a * variance_b / (variance_a + variance_b); };
  for (int i : missing_) {
    if (observed_[i]) continue;  // relabelled
    if (tracks_.has_last() && is_observed(tracks_.last_status(i))) {
      carry_.remember_gap_start(i, frame_, tracks_.last_positions(), tracks_.last_statuses());
      gap_offset_[i].setZero();  // set below when this frame has a neighbourhood rotation
    }
    Vec3 carried;
    double carried_variance = 0.0;
    const bool carry = carry_on && carry_.carried(i, frame_, current_, observed_, carried, carried_variance);
    // The neighbours' opinions (PCA, else eq. 2) with the carry, then the region's weighed in.
    Vec3 fused;
    double variance = 0.0;
    const bool pca = options_.use_pca && pca_estimate(i, fused, &variance, true) > 0;
    if (!pca && estimated_[i]) {
      fused = estimate_[i];
      variance = rigid_estimate_variance(i, true);
    }
    const bool near = pca || estimated_[i];
    if (near && carry) {
      fused = combine(fused, variance, carried, carried_variance);
      variance = combined_variance(variance, carried_variance);
    }
    Vec3 regional;
    double regional_variance = 0.0;
    const double other_variance = near ? variance : carry ? carried_variance : std::numeric_limits<double>::infinity();
    const bool region = region_estimate(i, other_variance, regional, regional_variance);
    if (near) {
      current_[i] = region ? combine(fused, variance, regional, regional_variance) : fused;
      status_[i] = pca ? MarkerStatus::FilledPca : MarkerStatus::FilledRigid;
    } else if (region) {
      current_[i] = carry ? combine(regional, regional_variance, carried, carried_variance) : regional;
      status_[i] = MarkerStatus::FilledPca;
      continue;  // no neighbourhood rotation for the continuity offset
    } else {
      // Held: carried with the rigid motion of the anchors (since the gap started, else since
      // the last frame), else kept where it was.
      Vec3 moved;
      if (carry)
        current_[i] = carried;
      else if (tracks_.has_last() && transfer_motion(model_.anchor_offsets[i], model_.anchor_offsets[i + 1],
                                                     model_.anchors, tracks_.last(i), moved))
        current_[i] = moved;
      else
        current_[i] = tracks_.has_last() ? tracks_.last(i) : model_.reference_positions[i];
      status_[i] = MarkerStatus::Held;
      continue;
    }

    // Continuity: the gap starts where the last measurement, moved with the neighbours, would be.
    // The offset is made at the gap's first frame (none if that frame has no neighbourhood
    // rotation to keep it in) and decays with the gap's age.
    if (decay_frames <= 0.0 || !has_rotation_[i] || !tracks_.has_last()) continue;
    Vec3 expected;
    if (is_observed(tracks_.last_status(i)) &&
        transfer_motion(model_.ring_offsets[i], model_.ring_offsets[i + 1], model_.ring, tracks_.last(i),
                        expected))
      gap_offset_[i] = rotation_[i].transpose() * (expected - current_[i]);
    const double age = static_cast<double>(frame_ - carry_.gap_start_frame(i));
    current_[i] += rotation_[i] * gap_offset_[i] * std::exp(-age / decay_frames);
  }
}

}  // namespace skinstream
