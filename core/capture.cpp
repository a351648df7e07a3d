#include "core/capture.h"

#include <stdexcept>

namespace skinstream {

bool is_unlabelled_name(const std::string& label) {
  if (label.empty()) return true;
  if (label[0] != '*') return false;
  if (label.size() == 1) return true;
  for (size_t i = 1; i < label.size(); ++i)
    if (label[i] < '0' || label[i] > '9') return false;
  return true;
}

Capture::Capture(std::vector<std::string> point_labels, int frames, double rate)
    : rate_hz(rate), labels(std::move(point_labels)), frame_count(frames) {
  positions.assign(static_cast<size_t>(frames) * labels.size(), missing_point());
}

std::vector<int> Capture::labelled_points() const {
  std::vector<int> out;
  for (int p = 0; p < point_count(); ++p)
    if (is_labelled(p)) out.push_back(p);
  return out;
}

std::vector<int> Capture::unlabelled_points() const {
  std::vector<int> out;
  for (int p = 0; p < point_count(); ++p)
    if (!is_labelled(p)) out.push_back(p);
  return out;
}

int Capture::label_index(const std::string& label) const {
  for (int p = 0; p < point_count(); ++p)
    if (labels[p] == label) return p;
  return -1;
}

Capture Capture::select(const std::vector<int>& points, int first, int count) const {
  if (first < 0 || count < 0 || first + count > frame_count) throw std::out_of_range("Capture::select frames");
  std::vector<std::string> names;
  for (int p : points) names.push_back(labels.at(p));
  Capture out(std::move(names), count, rate_hz);
  out.first_frame = first_frame + first;
  for (int f = 0; f < count; ++f)
    for (size_t i = 0; i < points.size(); ++i) out.at(f, static_cast<int>(i)) = at(first + f, points[i]);
  return out;
}

CaptureSummary summarize(const Capture& capture) {
  CaptureSummary s;
  const std::vector<int> labelled = capture.labelled_points();
  s.labelled = static_cast<int>(labelled.size());
  s.unlabelled = capture.point_count() - s.labelled;
  size_t missing = 0;
  for (int p : labelled) {
    int run_start = -1;
    for (int f = 0; f <= capture.frame_count; ++f) {
      const bool gone = f < capture.frame_count && !capture.present(f, p);
      if (gone) {
        ++missing;
        if (run_start < 0) run_start = f;
      } else if (run_start >= 0) {
        s.gaps.push_back({p, run_start, f - run_start});
        run_start = -1;
      }
    }
  }
  const size_t total = labelled.size() * static_cast<size_t>(capture.frame_count);
  s.missing_fraction = total ? static_cast<double>(missing) / static_cast<double>(total) : 0.0;
  return s;
}

}  // namespace skinstream
