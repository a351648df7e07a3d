#pragma once
// Park & Hodgins' Table 1 after merging: how the relabeller joined the partial trajectories a
// capture system delivered, judged against the true marker of every delivered sample (known
// for synthetic captures).

#include <vector>

#include "core/capture.h"
#include "core/marker_status.h"

namespace skinstream {

// One wrongly labelled fragment, for telling the kinds of error apart: which channel, when, whose
// it really was and which marker took it first.
struct WrongFragment {
  int channel = -1;
  int first_frame = 0, last_frame = 0;  // the fragment
  int first_wrong_frame = 0;
  int wrong_samples = 0;
  int true_marker = -1;  // at the first wrong sample; negative: a ghost
  int taken_by = -1;     // the marker that took that sample
  bool relabelled = false;  // taken as a free point (else kept as a labelled channel's measurement)
};

struct MergeStats {
  int fragments = 0;           // partial trajectories delivered: runs of samples on one channel
  int unmerged_fragments = 0;  // fragments no marker took a sample of
  int trajectories_after = 0;  // markers with any observed sample + unmerged fragments
  int wrong_fragments = 0;     // fragments with a sample given to a marker that is not its own
  // Of those, how the wrong sample got there: a labelled channel's sample kept as measured (a
  // mislabel the label check let stand) or a free point taken by the relabeller.
  int wrong_measured_fragments = 0;
  int wrong_relabelled_fragments = 0;
  long wrong_samples = 0;
  // Samples a labelled channel delivered of its own marker (the label was right) that the marker
  // did not keep: a true measurement the label check rejected and nobody gave back.
  long true_labels_not_kept = 0;
  std::vector<WrongFragment> wrong_list;  // every wrong fragment, by channel then frame
  double wrong_rate() const { return fragments ? static_cast<double>(wrong_fragments) / fragments : 0.0; }
};

// `true_marker`: per delivered sample (frame-major, delivered.point_count() per frame) the
// subject marker it really is, or a negative value for a ghost / no sample. `channel_of`: the
// channel of each subject marker (-1 none). `status` and `fragments` (frames x markers) as
// returned by fill_capture. Throws std::invalid_argument on mismatched sizes.
MergeStats merge_stats(const Capture& delivered, const std::vector<int>& true_marker, const std::vector<int>& channel_of,
                       const std::vector<MarkerStatus>& status, const std::vector<int>& fragments);

}  // namespace skinstream
