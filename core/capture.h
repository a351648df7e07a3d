#pragma once
// A marker capture in memory: points x frames of 3D positions in millimetres.
// A missing sample is NaN in all three coordinates; that is the only missing marker.

#include <Eigen/Core>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace skinstream {

using Vec3 = Eigen::Vector3d;

inline Vec3 missing_point() { return Vec3::Constant(std::numeric_limits<double>::quiet_NaN()); }
inline bool is_present(const Vec3& p) { return std::isfinite(p.x()) && std::isfinite(p.y()) && std::isfinite(p.z()); }

// Points whose label is empty or of the form "*N" (how Vicon and others name unlabelled
// reconstructions) are unlabelled: kept as their own channels, never dropped.
bool is_unlabelled_name(const std::string& label);

struct Capture {
  double rate_hz = 0.0;
  int first_frame = 1;              // frame number of frame index 0 (C3D FIRST_FRAME)
  std::vector<std::string> labels;  // one per point channel
  int frame_count = 0;
  std::vector<Vec3> positions;      // frame-major: positions[frame * point_count() + point]

  Capture() = default;
  Capture(std::vector<std::string> point_labels, int frames, double rate);

  int point_count() const { return static_cast<int>(labels.size()); }
  Vec3& at(int frame, int point) { return positions[static_cast<size_t>(frame) * labels.size() + point]; }
  const Vec3& at(int frame, int point) const {
    return positions[static_cast<size_t>(frame) * labels.size() + point];
  }
  bool present(int frame, int point) const { return is_present(at(frame, point)); }
  bool is_labelled(int point) const { return !is_unlabelled_name(labels[point]); }

  // Indices of labelled / unlabelled channels, in channel order.
  std::vector<int> labelled_points() const;
  std::vector<int> unlabelled_points() const;
  int label_index(const std::string& label) const;  // -1 when absent

  // A copy holding only the given channels (in that order) and frames [first, first + count).
  Capture select(const std::vector<int>& points, int first, int count) const;
};

// One gap: a run of missing frames of one labelled point.
struct Gap {
  int point = 0;
  int first_frame = 0;  // frame index
  int length = 0;
};

struct CaptureSummary {
  int labelled = 0;
  int unlabelled = 0;
  double missing_fraction = 0.0;  // over labelled samples
  std::vector<Gap> gaps;          // labelled points only; gaps at the start or end included
};

CaptureSummary summarize(const Capture& capture);

}  // namespace skinstream
