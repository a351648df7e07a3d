#pragma once
// The Vicon DataStream ("CGStream") wire format, as spoken by Vicon Nexus, Tracker and Shogun on
// TCP port 801 and read by the Vicon DataStream SDK. Pure bytes: no sockets.
//
// A packet is `u32 0x1A2B0001, u32 length` followed by `length` bytes of objects, each
// `u32 type, u32 length, payload`. Everything is native little-endian without padding; strings are
// `u32 length + bytes`, vectors and sets `u32 count + items`, bool one byte. Field orders follow the
// SDK's ViconCGStream/*.h Read()/Write() methods (note Timecode: standard before user bits).
// Positions are millimetres as float64; a labelled marker absent from LabeledRecons is occluded.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace skinstream::vicon {

constexpr uint32_t kPacketMagic = 0x1A2B0001;
constexpr size_t kPacketHeaderBytes = 8;
constexpr size_t kObjectHeaderBytes = 8;
constexpr uint32_t kMaxPacketLength = 16u << 20;  // larger is refused: no real frame comes near
constexpr int64_t kTicksPerSecond = 135'000'000;  // StreamInfo frame periods are in 135 MHz ticks
constexpr uint16_t kDefaultPort = 801;
constexpr uint16_t kDefaultMulticastPort = 44801;

// Object type ids (ViconCGStream/Enum.h); only the ones skinstream reads or writes.
namespace object_type {
constexpr uint32_t StreamInfo = 1;
constexpr uint32_t SubjectInfo = 2;
constexpr uint32_t FrameInfo = 5;
constexpr uint32_t LabeledRecons = 6;
constexpr uint32_t UnlabeledRecons = 7;
constexpr uint32_t Timecode = 23;
constexpr uint32_t ApexHaptics = 35;
constexpr uint32_t Ping = 42;
constexpr uint32_t ObjectEnums = 100001;
constexpr uint32_t RequestFrame = 100002;
constexpr uint32_t KeepAlive = 100003;
constexpr uint32_t Contents = 100004;
constexpr uint32_t StartMulticastSender = 100005;
constexpr uint32_t StopMulticastSender = 100006;
constexpr uint32_t Filter = 100007;
constexpr uint32_t RequestNextFrame = 100008;
}  // namespace object_type

const char* object_type_name(uint32_t type);  // "LabeledRecons", or "unknown"

// ---- Control objects (client <-> server) ----

struct ObjectEnums {  // the server's offer, then the client's choice: a set of type ids
  std::vector<uint32_t> types;  // written sorted and unique, as std::set is
};
struct RequestFrame {
  bool streaming = true;  // true: ServerPush (every frame); false: ClientPull (one frame)
};
struct RequestNextFrame {
  uint32_t count = 1;
};
struct Ping {
  uint64_t id = 0;
};
struct StartMulticastSender {
  uint32_t multicast_address = 0;  // IPv4 as a host-order integer (address_v4::to_uint())
  uint32_t source_address = 0;
  uint16_t port = kDefaultMulticastPort;
};
struct Contents {  // which objects a frame carries and which are unchanged since the last one
  std::vector<std::pair<uint32_t, uint32_t>> table;  // map<type, u32>, sorted by type
  std::vector<uint32_t> unchanged;                   // set<type>
};
struct Filter {  // map<type, set<filter id>>
  std::vector<std::pair<uint32_t, std::vector<uint32_t>>> filters;
};

// ---- Data objects (server -> client) ----

struct StreamInfo {
  int64_t frame_period_ticks = 0;  // 135 MHz ticks: 120 Hz = 1'125'000
};
struct SubjectSegment {
  uint32_t parent_id = 0;
  uint32_t segment_id = 0;
  std::array<float, 6> bounds{};
  std::string name;
};
struct SubjectMarker {
  uint32_t marker_id = 0;
  std::string name;
};
struct SubjectAttachment {
  uint32_t marker_id = 0;
  uint32_t segment_id = 0;
};
struct SubjectInfo {
  uint32_t subject_id = 0;
  std::string name;
  std::vector<SubjectSegment> segments;
  std::vector<SubjectMarker> markers;
  std::vector<SubjectAttachment> attachments;
};
struct FrameInfo {
  uint32_t frame_id = 0;  // the SDK reports frame_id + 1 as the frame number
};
struct LabeledRecon {
  uint32_t subject_id = 0;
  uint32_t marker_id = 0;
  double radius = 0.0;
  std::array<double, 3> position{};  // mm
  std::array<double, 9> covariance{};
  uint32_t trajectory_id = 0;
};
struct UnlabeledRecon {
  double radius = 0.0;
  std::array<double, 3> position{};  // mm
  std::array<double, 9> covariance{};
  uint32_t trajectory_id = 0;
};
struct Timecode {
  uint8_t hours = 0, minutes = 0, seconds = 0, frames = 0;
  uint16_t subframes = 0;
  uint16_t subframes_per_frame = 0;
  uint32_t standard = 0xFFFFFFFFu;  // PAL 0, NTSC 1, NTSCDrop 2, Film 3, NTSCFilm 4, ATSC 5; none = -1
  uint32_t user_bits = 0;
  uint8_t field_flag = 0;
};
constexpr uint32_t kTimecodeFilm = 3;

// What one source may describe, so that a broken or hostile server cannot make a client decode,
// remember or log without end (a SubjectInfo of 10,000 new names every frame). A packet beyond
// these is malformed. skinstreamd's source_max_* keys set them.
struct DescriptionLimits {
  uint32_t max_subjects = 128;              // SubjectInfo objects in one packet
  uint32_t max_markers_per_subject = 1024;  // markers of one SubjectInfo; its segments and attachments alike
  uint32_t max_name_bytes = 256;            // a subject's, segment's or marker's name
};

// The frame rates a StreamInfo may give, 1 Hz to 10 kHz (real systems run at 30 Hz to 2 kHz),
// as periods in ticks. Inside this range frame_id (u32) x period cannot overflow an int64.
constexpr int64_t kMinFramePeriodTicks = kTicksPerSecond / 10'000;  // 10 kHz
constexpr int64_t kMaxFramePeriodTicks = kTicksPerSecond;           // 1 Hz
static_assert(kMaxFramePeriodTicks <= INT64_MAX / UINT32_MAX, "frame_id x period must fit an int64");

// Bytes each record takes on the wire (for counts that must fit in what is left).
constexpr size_t kLabeledReconBytes = 4 + 4 + 8 + 3 * 8 + 9 * 8 + 4;  // 116
constexpr size_t kUnlabeledReconBytes = 8 + 3 * 8 + 9 * 8 + 4;        // 108

// Frame period <-> rate.
int64_t frame_period_ticks(double rate_hz);
double rate_from_period(int64_t frame_period_ticks);  // 0 when the period is not positive

}  // namespace skinstream::vicon
