#pragma once
// The daemon's Vicon DataStream client: connects to Vicon Nexus / Tracker / Shogun (or
// skinstream-replay) on TCP port 801, asks for frames and hands each one on as a SourceFrame
// (every subject with its labels; SubjectRouter then matches them to ours).
//
// Handshake: the server sends ObjectEnums; we answer with the types we read (StreamInfo,
// SubjectInfo, FrameInfo, LabeledRecons, UnlabeledRecons, Timecode, Contents) and RequestFrame
// {true} (ServerPush) or, in ClientPull, RequestFrame{false} after every frame.
// Any failure (refused, reset, end of stream, malformed packet, no ObjectEnums within
// handshake_timeout of connecting) closes the connection, reports Disconnected with the reason
// and retries after a backoff of 0.25 s doubling to 5 s; the backoff returns to 0.25 s once frames
// flow again (Streaming). A server that sends no frame for stall_timeout after the handshake
// (connected, but silent) is reported Stalled and retried the same way.
//
// Subjects: SourceFrame::subjects are the SubjectInfo objects (name, marker names in the order
// SubjectInfo lists them), decoded only when their bytes change (structure_version then bumps).
// A packet with SubjectInfo lists every subject; one with StreamInfo and no SubjectInfo says
// there are none (the last subject left). A LabeledRecon whose subject or marker id SubjectInfo
// does not list is passed on as an unlabelled point (reported once per connection).
//
// Frame numbers are those the SDK reports (FrameInfo + 1); source_time_ns = FrameInfo x period;
// the Timecode object is valid when its standard is one of the SDK's (the rate follows from it).
// After the first frames, receiving a frame allocates nothing.

#include <array>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <unordered_set>
#include <vector>

#include "protocol/vicon/vicon_datastream.h"
#include "protocol/vicon/vicon_packet_reader.h"
#include "server/asio.h"
#include "server/ingest/frame_source.h"
#include "server/ingest/source_frame.h"

namespace skinstream::server {

// Packet objects -> SourceFrame, shared by the TCP and the multicast sources.
class ViconFrameAssembler {
 public:
  // `limits` bound what a SubjectInfo may describe (its markers, its names).
  explicit ViconFrameAssembler(SourceSink& sink, const vicon::DescriptionLimits& limits = {});

  enum class Result { NoFrame, Frame, Malformed };
  // One packet's objects. On Frame, frame() holds it (receive_time_ns as given). Unknown object
  // types are reported to the sink once per type.
  Result handle(const std::vector<vicon::ObjectView>& objects, int64_t receive_time_ns, std::string& out_error);
  const SourceFrame& frame() const { return frame_; }

  bool saw_object_enums() const { return saw_object_enums_; }
  const vicon::ObjectEnums& offered() const { return offered_; }
  void reset();  // a new connection: forget the stream's static objects

 private:
  bool update_subjects(const std::vector<vicon::ObjectView>& objects, std::string& out_error);
  void add_unlabelled(const std::array<double, 3>& position, uint32_t trajectory_id);

  SourceSink& sink_;
  vicon::DescriptionLimits limits_;
  SourceFrame frame_;
  int64_t frame_period_ticks_ = 0;
  bool saw_object_enums_ = false;
  vicon::ObjectEnums offered_;
  // (subject id << 32 | marker id) -> (subject index << 32 | label index) in frame_; sorted.
  std::vector<std::pair<uint64_t, uint64_t>> label_slots_;
  std::vector<unsigned char> subject_bytes_;          // the SubjectInfo payloads last decoded
  std::vector<unsigned char> subject_bytes_scratch_;  // this packet's, to compare
  bool reported_unknown_marker_ = false;  // this connection
  std::unordered_set<uint32_t> reported_types_;
  std::vector<vicon::LabeledRecon> labeled_;
  std::vector<vicon::UnlabeledRecon> unlabeled_;
};

struct ViconSourceOptions {
  enum class Mode { ServerPush, ClientPull };
  std::string host = "127.0.0.1";
  uint16_t port = vicon::kDefaultPort;
  Mode mode = Mode::ServerPush;
  double initial_backoff_seconds = 0.25;
  double max_backoff_seconds = 5.0;
  std::chrono::milliseconds handshake_timeout{3000};  // connecting to ObjectEnums
  std::chrono::milliseconds stall_timeout{1000};      // without a frame after the handshake; 0: wait forever
  vicon::DescriptionLimits limits{};  // the subjects a packet may describe (beyond them: malformed)
};

class ViconSource : public FrameSource {
 public:
  ViconSource(asio::io_context& io, ViconSourceOptions options, SourceSink& sink);
  ~ViconSource() override;

  void start() override;
  void stop() override;

 private:
  struct State;
  std::shared_ptr<State> state_;
};

}  // namespace skinstream::server
