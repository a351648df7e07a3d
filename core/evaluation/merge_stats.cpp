#include "core/evaluation/merge_stats.h"

#include <stdexcept>

namespace skinstream {

MergeStats merge_stats(const Capture& delivered, const std::vector<int>& true_marker, const std::vector<int>& channel_of,
                       const std::vector<MarkerStatus>& status, const std::vector<int>& fragments) {
  const int channels = delivered.point_count(), frames = delivered.frame_count;
  const int markers = static_cast<int>(channel_of.size());
  const size_t samples = static_cast<size_t>(frames) * channels, outputs = static_cast<size_t>(frames) * markers;
  if (true_marker.size() != samples || status.size() != outputs || fragments.size() != outputs)
    throw std::invalid_argument("merge_stats: sizes do not match the capture and the subject");

  // Which marker took each delivered sample.
  std::vector<int> taken_by(samples, -1);
  std::vector<char> relabelled(samples, 0);
  std::vector<char> marker_seen(markers, 0);
  for (int f = 0; f < frames; ++f)
    for (int m = 0; m < markers; ++m) {
      const size_t at = static_cast<size_t>(f) * markers + m;
      int channel = -1;
      if (status[at] == MarkerStatus::Measured) channel = channel_of[m];
      else if (status[at] == MarkerStatus::Relabelled) channel = fragments[at];
      if (channel < 0 || channel >= channels) continue;
      taken_by[static_cast<size_t>(f) * channels + channel] = m;
      relabelled[static_cast<size_t>(f) * channels + channel] = status[at] == MarkerStatus::Relabelled;
      marker_seen[m] = 1;
    }

  MergeStats s;
  for (int c = 0; c < channels; ++c) {
    for (int f = 0; f < frames;) {
      if (!delivered.present(f, c)) {
        ++f;
        continue;
      }
      bool used = false, wrong = false, wrong_measured = false, wrong_relabelled = false;
      WrongFragment record;
      record.channel = c;
      record.first_frame = f;
      for (; f < frames && delivered.present(f, c); ++f) {
        const size_t at = static_cast<size_t>(f) * channels + c;
        if (taken_by[at] < 0) continue;
        used = true;
        if (taken_by[at] != true_marker[at]) {
          if (!wrong) {
            record.first_wrong_frame = f;
            record.true_marker = true_marker[at];
            record.taken_by = taken_by[at];
            record.relabelled = relabelled[at];
          }
          wrong = true;
          (relabelled[at] ? wrong_relabelled : wrong_measured) = true;
          ++s.wrong_samples;
          ++record.wrong_samples;
        }
      }
      record.last_frame = f - 1;
      if (wrong) s.wrong_list.push_back(record);
      ++s.fragments;
      s.unmerged_fragments += !used;
      s.wrong_fragments += wrong;
      s.wrong_measured_fragments += wrong_measured;
      s.wrong_relabelled_fragments += wrong_relabelled;
    }
  }
  for (int m = 0; m < markers; ++m) {
    const int c = channel_of[m];
    if (c < 0 || c >= channels) continue;
    for (int f = 0; f < frames; ++f) {
      const size_t at = static_cast<size_t>(f) * channels + c;
      s.true_labels_not_kept += delivered.present(f, c) && true_marker[at] == m && taken_by[at] != m;
    }
  }
  for (char seen : marker_seen) s.trajectories_after += seen;
  s.trajectories_after += s.unmerged_fragments;
  return s;
}

}  // namespace skinstream
