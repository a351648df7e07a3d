#include "core/local_smoothing.h"

#include <algorithm>

#include "core/neighbourhood_transform.h"

namespace skinstream {
namespace {

// Repeated x <- x - lambda * D4 x over a short sequence, ends replicated.
void smooth_sequence(Vec3* x, Vec3* scratch, int count, const SmoothingOptions& o) {
  if (count < 3) return;
  auto at = [&](int t) -> const Vec3& { return x[std::clamp(t, 0, count - 1)]; };
  for (int it = 0; it < o.iterations; ++it) {
    for (int t = 0; t < count; ++t)
      scratch[t] = x[t] - o.lambda * (at(t - 2) - 4.0 * at(t - 1) + 6.0 * x[t] - 4.0 * at(t + 1) + at(t + 2));
    std::copy(scratch, scratch + count, x);
  }
}

}  // namespace

void smooth_offline(const SubjectModel& model, std::vector<Vec3>& positions, int frames, const SmoothingOptions& options) {
  const int n = model.marker_count();
  std::vector<RigidTransform> transforms(frames);
  std::vector<char> ok(frames);
  std::vector<Vec3> local(frames), scratch(frames);
  for (int i = 0; i < n; ++i) {
    for (int f = 0; f < frames; ++f) {
      const std::span<const Vec3> frame(&positions[static_cast<size_t>(f) * n], n);
      ok[f] = neighbourhood_transform(model, i, frame, {}, transforms[f]);
      local[f] = ok[f] ? transforms[f].apply_inverse(frame[i]) : frame[i];
    }
    // Smooth each run of frames where the local frame exists.
    for (int start = 0; start < frames;) {
      int end = start;
      while (end < frames && ok[end] == ok[start]) ++end;
      if (ok[start]) smooth_sequence(&local[start], &scratch[start], end - start, options);
      start = end;
    }
    for (int f = 0; f < frames; ++f)
      if (ok[f]) positions[static_cast<size_t>(f) * n + i] = transforms[f].apply(local[f]);
  }
}

OnlineSmoother::OnlineSmoother(const SubjectModel& model, const SmoothingOptions& options)
    : model_(model), options_(options), n_(model.marker_count()) {
  options_.past = std::max(0, options_.past);
  options_.lookahead = std::max(0, options_.lookahead);
  capacity_ = options_.past + 1 + options_.lookahead;
  local_.assign(static_cast<size_t>(capacity_) * n_, Vec3::Zero());
  transforms_.assign(static_cast<size_t>(capacity_) * n_, RigidTransform{});
  has_transform_.assign(static_cast<size_t>(capacity_) * n_, 0);
  world_.assign(static_cast<size_t>(capacity_) * n_, Vec3::Zero());
  status_.assign(static_cast<size_t>(capacity_) * n_, MarkerStatus::Held);
  frame_numbers_.assign(capacity_, 0);
  window_.assign(capacity_, Vec3::Zero());
  scratch_.assign(capacity_, Vec3::Zero());
}

int OnlineSmoother::slot(int age) const { return ((newest_ - age) % capacity_ + capacity_) % capacity_; }

bool OnlineSmoother::push(std::span<const Vec3> positions, std::span<const MarkerStatus> status, long frame_number,
                          const FrameOutput& out, long& out_frame_number) {
  newest_ = (newest_ + 1) % capacity_;
  count_ = std::min(count_ + 1, capacity_);
  ++pending_;
  const size_t base = static_cast<size_t>(newest_) * n_;
  for (int i = 0; i < n_; ++i) {
    RigidTransform& t = transforms_[base + i];
    has_transform_[base + i] = neighbourhood_transform(model_, i, positions, {}, t);
    local_[base + i] = has_transform_[base + i] ? t.apply_inverse(positions[i]) : positions[i];
    world_[base + i] = positions[i];
    status_[base + i] = status[i];
  }
  frame_numbers_[newest_] = frame_number;
  if (pending_ <= options_.lookahead) return false;
  --pending_;
  return release(options_.lookahead, out, out_frame_number);
}

bool OnlineSmoother::drain(const FrameOutput& out, long& out_frame_number) {
  if (pending_ == 0) return false;
  --pending_;
  return release(pending_, out, out_frame_number);  // the oldest frame not yet released
}

bool OnlineSmoother::release(int age, const FrameOutput& out, long& out_frame_number) {
  const int oldest_age = count_ - 1;
  const int released = slot(age);
  for (int i = 0; i < n_; ++i) {
    const size_t at = static_cast<size_t>(released) * n_ + i;
    out.status[i] = status_[at];
    if (!has_transform_[at]) {
      out.positions[i] = world_[at];
      continue;
    }
    // The window: consecutive frames with a local frame around the released one.
    int first = age, last = age;
    while (first + 1 <= oldest_age && has_transform_[static_cast<size_t>(slot(first + 1)) * n_ + i]) ++first;
    while (last - 1 >= 0 && has_transform_[static_cast<size_t>(slot(last - 1)) * n_ + i]) --last;
    int count = 0, index = 0;
    for (int a = first; a >= last; --a) {
      if (a == age) index = count;
      window_[count++] = local_[static_cast<size_t>(slot(a)) * n_ + i];
    }
    smooth_sequence(window_.data(), scratch_.data(), count, options_);
    out.positions[i] = transforms_[at].apply(window_[index]);
  }
  out_frame_number = frame_numbers_[released];
  return true;
}

}  // namespace skinstream
