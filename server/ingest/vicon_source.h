#pragma once
// The daemon's Vicon DataStream client: connects to Vicon Nexus / Tracker / Shogun (or
// skinstream-replay) on TCP port 801, asks for frames and hands each one to a FrameSink in the
// subject's marker order.
//
// Handshake: the server sends ObjectEnums; we answer with the types we read (StreamInfo,
// SubjectInfo, FrameInfo, LabeledRecons, UnlabeledRecons, Timecode, Contents) and RequestFrame
// {true} (ServerPush) or, in ClientPull, RequestFrame{false} after every frame.
// Any failure (refused, reset, end of stream, malformed packet) closes the connection, reports
// Disconnected with the reason and retries after a backoff of 0.25 s doubling to 5 s; the backoff
// returns to 0.25 s once frames flow again (Streaming).
//
// Marker mapping: SubjectInfo marker names are matched to the subject's marker names. Every
// subject with at least one matching name is used (several Vicon subjects may split one body);
// its markers whose names the subject does not have are reported once each (on_unknown_label)
// and then passed on as unlabelled points. Subjects with no matching name (another performer)
// are ignored. SubjectInfo is decoded only when its bytes change.
//
// Frame numbers are those the SDK reports (FrameInfo + 1); source_time_ns = FrameInfo x period.
// After the first frames, receiving a frame allocates nothing.

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <unordered_set>
#include <vector>

#include "protocol/vicon_datastream.h"
#include "protocol/vicon_packet_reader.h"
#include "server/asio.h"
#include "server/ingest/frame_source.h"
#include "server/ingest/marker_frame.h"

namespace skinstream::server {

// Packet objects -> MarkerFrame, shared by the TCP and the multicast sources.
class ViconFrameAssembler {
 public:
  ViconFrameAssembler(std::vector<std::string> marker_names, FrameSink& sink);

  enum class Result { NoFrame, Frame, Malformed };
  // One packet's objects. On Frame, frame() holds it (receive_time_ns as given). Unknown object
  // types are reported to the sink once per type.
  Result handle(const std::vector<vicon::ObjectView>& objects, int64_t receive_time_ns, std::string& out_error);
  const MarkerFrame& frame() const { return frame_; }

  bool saw_object_enums() const { return saw_object_enums_; }
  const vicon::ObjectEnums& offered() const { return offered_; }
  void reset();  // a new connection: forget the stream's static objects

 private:
  bool update_subjects(const std::vector<vicon::ObjectView>& objects, std::string& out_error);

  std::vector<std::string> marker_names_;
  FrameSink& sink_;
  MarkerFrame frame_;
  int64_t frame_period_ticks_ = 0;
  bool saw_object_enums_ = false;
  vicon::ObjectEnums offered_;
  // (subject id << 32 | marker id) -> subject marker index, kUnknownLabel or kIgnored; sorted.
  static constexpr int kUnknownLabel = -1;
  static constexpr int kIgnored = -2;
  std::vector<std::pair<uint64_t, int>> marker_map_;
  std::vector<unsigned char> subject_bytes_;          // the SubjectInfo payloads last decoded
  std::vector<unsigned char> subject_bytes_scratch_;  // this packet's, to compare
  std::unordered_set<std::string> reported_labels_;
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
};

class ViconSource : public FrameSource {
 public:
  // marker_names: the subject's markers, in the order MarkerFrame::labelled uses.
  ViconSource(asio::io_context& io, ViconSourceOptions options, std::vector<std::string> marker_names,
              FrameSink& sink);
  ~ViconSource() override;

  void start() override;
  void stop() override;

 private:
  struct State;
  std::shared_ptr<State> state_;
};

}  // namespace skinstream::server
