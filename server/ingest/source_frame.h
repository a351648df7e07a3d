#pragma once
// A capture system's frame as it arrives, before it is matched to our subjects: what every
// source (Vicon DataStream over TCP or multicast, QTM RT, NatNet, file replay) hands on. The
// source only decodes; matching labels to each subject's markers happens once, after it, for
// every source alike (several actors wear one marker template, so a label means something only
// within its subject).
//
// A source keeps one SourceFrame and refills it for every frame: the vectors keep their
// capacity, so steady state allocates nothing. `subjects` changes only when the capture
// system's description changes (Vicon SubjectInfo, QTM 3D parameters, NatNet model
// definitions); the source then bumps `structure_version`, so the matching can be redone only
// then.

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "core/capture.h"

namespace skinstream::server {

// SMPTE timecode of the frame, when the capture system sends one.
struct SourceTimecode {
  bool valid = false;
  uint8_t hours = 0, minutes = 0, seconds = 0, frames = 0;
  uint16_t subframe = 0;
  uint16_t subframes_per_frame = 0;
  float rate_hz = 0.0f;  // timecode frames per second (24, 25, 29.97, 30, ...)
  bool drop_frame = false;
  bool field = false;
};

// One subject (Vicon subject, NatNet marker set, a QTM label prefix) and its labelled markers,
// in the order SourceFrame::labelled gives their positions.
struct SourceSubject {
  std::string name;
  std::vector<std::string> labels;
};

// Whether the capture system says it is recording a take of its own (NatNet's frame flag, QTM's
// capture events); Vicon DataStream does not say.
enum class CaptureRecording : uint8_t { Unknown, Recording, NotRecording };

struct SourceFrame {
  uint32_t frame_number = 0;   // as the capture system's SDK reports it
  int64_t source_time_ns = 0;  // capture time (timecode, or frame x period)
  int64_t receive_time_ns = 0;  // wall clock (system_clock, ns since the epoch) when complete
  // How long the capture system says the frame took from its cameras' exposure to leaving it
  // (its own clock: NatNet's transmit minus mid-exposure stamps); -1 when it does not say.
  int64_t capture_latency_ns = -1;
  double rate_hz = 0.0;         // the source's frame rate; 0 when not known yet
  SourceTimecode timecode;
  CaptureRecording capture_recording = CaptureRecording::Unknown;

  uint64_t structure_version = 0;  // changes whenever `subjects` changed
  std::vector<SourceSubject> subjects;
  // Per subject, per label: the position in mm, NaN for occluded (not measured this frame).
  std::vector<std::vector<Vec3>> labelled;
  std::vector<Vec3> unlabelled;    // points without a label this frame
  std::vector<int> unlabelled_ids;  // the source's trajectory id per unlabelled point, -1 unknown
};

enum class SourceState {
  Connecting,    // trying to reach the source (with backoff after a failure)
  Streaming,     // frames arriving
  Disconnected,  // the source went away, refused, or did not finish its handshake; retrying
  Finished,      // a replay reached its end (without --loop), or a QTM measurement ended
  Stalled,       // connected, but no frame for the stall time: reconnecting (Disconnected on the wire)
};

const char* to_string(SourceState state);

// What every source talks to. Sources run on the daemon's network io_context and call the
// sink from that thread; the sink must not block.
class SourceSink {
 public:
  virtual ~SourceSink() = default;
  // A complete frame. The reference is valid only during the call: copy what is needed.
  virtual void on_frame(const SourceFrame& frame) = 0;
  virtual void on_source_state(SourceState state, std::string_view detail) = 0;
  // Input that was dropped: a malformed or truncated packet, an unknown object, a short read.
  // `what` is a short fixed category for metrics ("malformed_packet", "unknown_object", ...),
  // `detail` the human-readable reason for the (rate-limited) log.
  virtual void on_bad_input(std::string_view what, std::string_view detail) = 0;
};

}  // namespace skinstream::server
