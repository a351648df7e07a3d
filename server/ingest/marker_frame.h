#pragma once
// One frame of one subject's markers as the pipeline takes it, in the subject's marker order: a
// source's SourceFrame after SubjectRouter matched its labels to the subject's markers. Sized
// once for the subject (labelled = marker count, unlabelled capacity fixed) and reused: filling
// it allocates nothing.

#include <cstdint>
#include <vector>

#include "core/capture.h"
#include "server/ingest/source_frame.h"

namespace skinstream::server {

struct MarkerFrame {
  static constexpr int kMaxUnlabelled = 1024;  // GapFiller::kMaxFreePoints

  uint32_t frame_number = 0;         // as the source numbers it
  int64_t source_time_ns = 0;        // capture time: the source's timecode or frame * period
  int64_t receive_time_ns = 0;       // wall clock (system_clock, ns since epoch) when complete
  int64_t capture_latency_ns = -1;   // SourceFrame::capture_latency_ns
  double source_rate_hz = 0.0;       // from the source (StreamInfo frame period, file rate)
  SourceTimecode timecode;           // the source's SMPTE timecode, when it sends one

  std::vector<Vec3> labelled;        // one per subject marker, NaN = missing
  std::vector<Vec3> unlabelled;      // capacity kMaxUnlabelled; the first unlabelled_count used
  std::vector<int> unlabelled_ids;   // trajectory id per unlabelled point (-1 = unknown)
  int unlabelled_count = 0;

  int unknown_labels = 0;            // labelled points whose name the subject does not have
  int rejected_points = 0;           // neither a position nor NaN, or beyond the unlabelled capacity
  int implausible_points = 0;        // finite, but outside the capture volume (SubjectRouter)

  explicit MarkerFrame(int marker_count = 0) { resize(marker_count); }
  void resize(int marker_count) {
    labelled.assign(static_cast<size_t>(marker_count), missing_point());
    unlabelled.assign(kMaxUnlabelled, missing_point());
    unlabelled_ids.assign(kMaxUnlabelled, -1);
    unlabelled_count = 0;
  }
  // Back to "nothing seen" without allocating.
  void clear() {
    for (Vec3& p : labelled) p = missing_point();
    unlabelled_count = 0;
    unknown_labels = 0;
    rejected_points = 0;
    implausible_points = 0;
    timecode = SourceTimecode{};
  }
};

}  // namespace skinstream::server
