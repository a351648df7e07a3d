#pragma once
// Runs the online pipeline (gap filler -> lookahead blend -> optional smoothing) over a whole
// capture, frame by frame exactly as the daemon would, and collects the result. Also the
// place that maps a capture's channels onto the subject's markers by label.

#include <string>
#include <vector>

#include "core/capture.h"
#include "core/gap_filler.h"
#include "core/local_smoothing.h"
#include "core/subject_model.h"

namespace skinstream {

enum class SmoothingMode { None, Online, Offline };

struct CaptureFillOptions {
  GapFillerOptions filler;
  int lookahead = 0;  // frames; the gap-end blend and the confirmation of new relabels (0 = strictly causal)
  SmoothingMode smoothing = SmoothingMode::None;
  SmoothingOptions smoothing_options;
};

struct CaptureFillReport {
  long measured = 0, relabelled = 0, filled = 0, held = 0, rejected_labels = 0;
  long changed_measured = 0;  // labelled samples the filler replaced (before any smoothing)
  std::vector<std::string> unknown_labels;   // labelled channels the subject does not have: used as unlabelled
  std::vector<std::string> absent_markers;   // subject markers with no channel in the capture
  int latency_frames = 0;                    // lookahead + online smoothing lookahead
};

// Which capture channel holds each subject marker (-1: none); channels not used are free points.
std::vector<int> map_channels_to_markers(const SubjectModel& model, const Capture& capture,
                                         CaptureFillReport* out_report = nullptr);

// The filled capture has the subject's markers as channels, in the subject's order.
// `out_status` (frames x markers) says what was done to each sample.
// `out_fragments` (frames x markers): the input channel whose point stood for each relabelled
// sample (a rejected labelled channel too), -1 otherwise; see FrameOutput::fragments.
Capture fill_capture(const SubjectModel& model, const Capture& input, const CaptureFillOptions& options,
                     std::vector<MarkerStatus>* out_status = nullptr, CaptureFillReport* out_report = nullptr,
                     std::vector<int>* out_fragments = nullptr);

}  // namespace skinstream
