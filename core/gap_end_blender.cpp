#include "core/gap_end_blender.h"

#include <algorithm>

#include "core/neighbourhood_transform.h"

namespace skinstream {

GapEndBlender::GapEndBlender(const SubjectModel& model, int lookahead)
    : model_(model), lookahead_(std::max(0, lookahead)), n_(model.marker_count()), capacity_(lookahead_ + 1) {
  positions_.assign(static_cast<size_t>(capacity_) * n_, Vec3::Zero());
  status_.assign(static_cast<size_t>(capacity_) * n_, MarkerStatus::Held);
  frame_numbers_.assign(capacity_, 0);
}

int GapEndBlender::slot(int age) const { return ((newest_ - age) % capacity_ + capacity_) % capacity_; }

void GapEndBlender::blend_gap_end(int marker) {
  const std::span<const Vec3> now(&positions_[static_cast<size_t>(slot(0)) * n_], n_);
  const std::span<const Vec3> before(&positions_[static_cast<size_t>(slot(1)) * n_], n_);
  RigidTransform t_now, t_before;
  if (!neighbourhood_transform(model_, marker, now, {}, t_now) ||
      !neighbourhood_transform(model_, marker, before, {}, t_before))
    return;
  // Where the marker sits relative to its neighbours: measured now vs estimated a frame ago.
  const Vec3 jump = t_now.apply_inverse(now[marker]) - t_before.apply_inverse(before[marker]);
  for (int age = 1; age < held_; ++age) {
    const size_t base = static_cast<size_t>(slot(age)) * n_;
    const MarkerStatus s = status_[base + marker];
    if (s != MarkerStatus::FilledPca && s != MarkerStatus::FilledRigid) break;
    RigidTransform t;
    if (!neighbourhood_transform(model_, marker, {&positions_[base], static_cast<size_t>(n_)}, {}, t)) break;
    const double weight = static_cast<double>(lookahead_ + 1 - age) / lookahead_;
    positions_[base + marker] += t.rotation * jump * weight;
  }
}

// The held frames in which `marker` stood on a fragment now revoked (the `frames` before the
// newest): estimates instead, its place relative to its neighbourhood (eq. 2's rigid fit)
// interpolated from the frame before them (when still held) to the newest frame, which the
// filler already filled.
void GapEndBlender::give_back(int marker, int frames) {
  const int span = std::min(frames, held_ - 1);
  const int before_age = span + 1 < held_ ? span + 1 : 0;  // the newest again when not held
  RigidTransform t_now, t_before;
  if (!neighbourhood_transform(model_, marker, frame(0), {}, t_now) ||
      !neighbourhood_transform(model_, marker, frame(before_age), {}, t_before))
    t_now = t_before = RigidTransform{};  // no neighbourhood: in world coordinates
  const Vec3 local_now = t_now.apply_inverse(frame(0)[marker]);
  const Vec3 local_before = t_before.apply_inverse(frame(before_age)[marker]);
  for (int age = 1; age <= span; ++age) {
    const size_t base = static_cast<size_t>(slot(age)) * n_;
    if (status_[base + marker] != MarkerStatus::Relabelled) continue;
    RigidTransform t;
    if (!neighbourhood_transform(model_, marker, frame(age), {}, t)) t = t_now;
    const double w = static_cast<double>(age) / (span + 1);  // 0 at the newest, 1 at the frame before
    positions_[base + marker] = t.apply((1.0 - w) * local_now + w * local_before);
    status_[base + marker] = MarkerStatus::FilledRigid;
  }
}

std::span<const Vec3> GapEndBlender::frame(int age) const {
  return {&positions_[static_cast<size_t>(slot(age)) * n_], static_cast<size_t>(n_)};
}

bool GapEndBlender::push(std::span<const Vec3> positions, std::span<const MarkerStatus> status, long frame_number,
                         const FrameOutput& out, long& out_frame_number, std::span<const int> revoked) {
  newest_ = (newest_ + 1) % capacity_;
  const size_t base = static_cast<size_t>(newest_) * n_;
  std::copy(positions.begin(), positions.end(), positions_.begin() + base);
  std::copy(status.begin(), status.end(), status_.begin() + base);
  frame_numbers_[newest_] = frame_number;
  held_ = std::min(held_ + 1, capacity_);
  if (static_cast<int>(revoked.size()) == n_)
    for (int i = 0; i < n_; ++i)
      if (revoked[i] > 0) give_back(i, revoked[i]);

  if (lookahead_ > 0 && held_ > 1) {
    const size_t previous = static_cast<size_t>(slot(1)) * n_;
    for (int i = 0; i < n_; ++i) {
      const bool filled_before = status_[previous + i] == MarkerStatus::FilledPca || status_[previous + i] == MarkerStatus::FilledRigid;
      if (filled_before && is_observed(status_[base + i])) blend_gap_end(i);
    }
  }
  if (held_ < capacity_) return false;
  return drain(out, out_frame_number);
}

bool GapEndBlender::drain(const FrameOutput& out, long& out_frame_number) {
  if (held_ == 0) return false;
  const int oldest = slot(held_ - 1);
  const size_t base = static_cast<size_t>(oldest) * n_;
  std::copy(positions_.begin() + base, positions_.begin() + base + n_, out.positions.begin());
  std::copy(status_.begin() + base, status_.begin() + base + n_, out.status.begin());
  out_frame_number = frame_numbers_[oldest];
  --held_;
  return true;
}

}  // namespace skinstream
