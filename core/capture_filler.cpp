#include "core/capture_filler.h"

#include "core/gap_end_blender.h"

namespace skinstream {

std::vector<int> map_channels_to_markers(const SubjectModel& model, const Capture& capture, CaptureFillReport* out_report) {
  std::vector<int> channel_of(model.marker_count(), -1);
  for (int c = 0; c < capture.point_count(); ++c) {
    if (!capture.is_labelled(c)) continue;
    const int m = model.marker_index(capture.labels[c]);
    if (m >= 0 && channel_of[m] < 0) channel_of[m] = c;
    else if (out_report) out_report->unknown_labels.push_back(capture.labels[c]);
  }
  if (out_report)
    for (int m = 0; m < model.marker_count(); ++m)
      if (channel_of[m] < 0) out_report->absent_markers.push_back(model.marker_names[m]);
  return channel_of;
}

Capture fill_capture(const SubjectModel& model, const Capture& input, const CaptureFillOptions& options,
                     std::vector<MarkerStatus>* out_status, CaptureFillReport* out_report,
                     std::vector<int>* out_fragments) {
  CaptureFillReport report;
  const std::vector<int> channel_of = map_channels_to_markers(model, input, &report);
  std::vector<char> is_marker_channel(input.point_count(), 0);
  for (int c : channel_of)
    if (c >= 0) is_marker_channel[c] = 1;
  std::vector<int> free_channels;
  for (int c = 0; c < input.point_count(); ++c)
    if (!is_marker_channel[c]) free_channels.push_back(c);

  const int n = model.marker_count();
  Capture filled(model.marker_names, input.frame_count, input.rate_hz);
  filled.first_frame = input.first_frame;
  std::vector<MarkerStatus> status(static_cast<size_t>(input.frame_count) * n, MarkerStatus::Held);

  GapFillerOptions filler_options = options.filler;
  filler_options.rate_hz = input.rate_hz > 0 ? input.rate_hz : filler_options.rate_hz;
  filler_options.confirm_frames = options.lookahead;  // relabels confirmed within the lookahead
  GapFiller filler(model, filler_options);
  GapEndBlender blender(model, options.lookahead);
  OnlineSmoother smoother(model, options.smoothing_options);
  const bool online_smoothing = options.smoothing == SmoothingMode::Online;
  report.latency_frames = options.lookahead + (online_smoothing ? options.smoothing_options.lookahead : 0);

  std::vector<Vec3> measured(n), filled_frame(n), free_points, stage_positions(n), final_positions(n);
  std::vector<int> free_ids;
  std::vector<MarkerStatus> frame_status(n), stage_status(n), final_status(n);
  std::vector<int> frame_fragments(n), frame_revoked(n);
  const FrameOutput filler_out{filled_frame, frame_status, frame_fragments, frame_revoked};
  if (out_fragments) out_fragments->assign(static_cast<size_t>(input.frame_count) * n, -1);
  const FrameOutput stage_out{stage_positions, stage_status};
  const FrameOutput final_out{final_positions, final_status};

  auto store = [&](long frame, const FrameOutput& out) {
    for (int m = 0; m < n; ++m) {
      filled.at(static_cast<int>(frame), m) = out.positions[m];
      status[static_cast<size_t>(frame) * n + m] = out.status[m];
    }
  };
  // Blender output goes through the online smoother when it is on.
  auto after_blend = [&](long frame) {
    long released;
    if (!online_smoothing) return store(frame, stage_out);
    if (smoother.push(stage_positions, stage_status, frame, final_out, released)) store(released, final_out);
  };

  for (int f = 0; f < input.frame_count; ++f) {
    for (int m = 0; m < n; ++m) measured[m] = channel_of[m] >= 0 ? input.at(f, channel_of[m]) : missing_point();
    free_points.clear();
    free_ids.clear();
    for (int c : free_channels)
      if (input.present(f, c)) {
        free_points.push_back(input.at(f, c));
        free_ids.push_back(c);  // a channel is one trajectory fragment
      }
    const FillStats stats = filler.run({measured, free_points, free_ids}, filler_out);
    report.measured += stats.measured;
    report.relabelled += stats.relabelled;
    report.filled += stats.filled;
    report.held += stats.held;
    report.rejected_labels += stats.rejected_labels;
    report.changed_measured += stats.changed_measured;
    if (out_fragments)
      for (int m = 0; m < n; ++m) {
        const int id = frame_fragments[m];
        // Free ids are channel numbers; a rejected labelled point of marker j is -(j + 1).
        (*out_fragments)[static_cast<size_t>(f) * n + m] = id == kNoFragment ? -1 : id >= 0 ? id : channel_of[-id - 1];
      }
    long released;
    if (blender.push(filled_frame, frame_status, f, stage_out, released, frame_revoked)) after_blend(released);
  }
  long released;
  while (blender.drain(stage_out, released)) after_blend(released);
  if (online_smoothing)
    while (smoother.drain(final_out, released)) store(released, final_out);

  if (options.smoothing == SmoothingMode::Offline) smooth_offline(model, filled.positions, filled.frame_count, options.smoothing_options);
  if (out_status) *out_status = std::move(status);
  if (out_report) *out_report = std::move(report);
  return filled;
}

}  // namespace skinstream
