#pragma once
// OptiTrack NatNet (Motive's streaming protocol), as the NatNet SDK's clients read it: UDP
// datagrams, each one message `u16 message id, u16 payload bytes, payload`, little-endian, no
// padding. Pure bytes: no sockets.
//
// Commands go to the server's command port (1510) and are answered to the sender; frames go to
// the data port (1511) of multicast group 239.255.42.99, or, unicast, to each client that
// connected (here: to the address it sent NAT_CONNECT from, the socket it keeps alive).
//
//   CONNECT (0)          opaque to the server (client name and wanted version)
//   SERVERINFO (1)       char name[256], u8 app version[4], u8 NatNet version[4],
//                        u64 clock ticks/s, u16 data port, u8 multicast, u8 group[4]
//   REQUEST_MODELDEF (4) empty
//   MODELDEF (5)         i32 count, per description: i32 type [4.1+: i32 bytes], then
//                        marker set (0): name\0, i32 n, n x name\0  (rigid bodies 1 and
//                        skeletons 2 are skipped by their layout, other types only from 4.1)
//   FRAMEOFDATA (7)      i32 frame number;
//                        marker sets: i32 n [4.1+: i32 bytes], per set: name\0, i32 m, m x f32 xyz;
//                        other markers: i32 n [4.1+: bytes], n x f32 xyz;
//                        rigid bodies: i32 n [4.1+: bytes], n x (i32 id, f32 xyz, f32 qxyzw,
//                          f32 error, i16 params);
//                        skeletons: i32 n [4.1+: bytes], per skeleton: i32 id, i32 m, m rigid bodies;
//                        [4.1+: assets: i32 n, i32 bytes, skipped by their bytes;]
//                        labelled markers: i32 n [4.1+: bytes], n x (i32 id = model << 16 | member,
//                          f32 xyz, f32 size, i16 params, f32 residual);
//                        force plates, devices: i32 n [4.1+: bytes], per item: i32 id, i32 channels,
//                          per channel: i32 k, k x f32;
//                        u32 timecode (hh mm ss ff, a byte each, hours highest), u32 subframe,
//                        f64 timestamp (s), u64 mid-exposure, u64 data received, u64 transmit
//                        (clock ticks) [4.0+: u32 precise seconds, u32 fraction], i16 params,
//                        i32 end-of-data 0 (optional when reading)
// Positions are metres on the wire; skinstream converts to and from millimetres at its edges.
// Layouts 3.0 to 4.1 (and later 4.x) are read and written; older ones are refused.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace skinstream::natnet {

using Bytes = std::span<const unsigned char>;

constexpr uint16_t kCommandPort = 1510;
constexpr uint16_t kDataPort = 1511;
constexpr const char* kMulticastGroup = "239.255.42.99";
constexpr size_t kHeaderBytes = 4;
constexpr size_t kMaxMessageBytes = kHeaderBytes + 65535;  // the u16 byte count's reach
constexpr size_t kMaxDatagramBytes = 65507;                // what one IPv4 UDP datagram carries

namespace message {
constexpr uint16_t Connect = 0;
constexpr uint16_t ServerInfo = 1;
constexpr uint16_t Request = 2;
constexpr uint16_t Response = 3;
constexpr uint16_t RequestModelDef = 4;
constexpr uint16_t ModelDef = 5;
constexpr uint16_t RequestFrameOfData = 6;
constexpr uint16_t FrameOfData = 7;
constexpr uint16_t MessageString = 8;
constexpr uint16_t Disconnect = 9;
constexpr uint16_t KeepAlive = 10;
constexpr uint16_t UnrecognizedRequest = 100;
}  // namespace message

// Labelled marker params bits.
constexpr int16_t kMarkerOccluded = 0x01;
constexpr int16_t kMarkerPointCloudSolved = 0x02;
constexpr int16_t kMarkerModelSolved = 0x04;
constexpr int16_t kMarkerHasModel = 0x08;
constexpr int16_t kMarkerUnlabelled = 0x10;
// Frame params bits.
constexpr int16_t kFrameRecording = 0x01;  // Motive is recording a take
constexpr int16_t kFrameTrackedModelsChanged = 0x02;

struct Version {
  int major = 4;
  int minor = 1;
  bool has_section_bytes() const { return major > 4 || (major == 4 && minor >= 1); }  // 4.1+
  bool has_precise_timestamp() const { return major >= 4; }
  bool supported() const { return major >= 3; }
};

struct ServerInfo {
  std::string application_name = "skinstream";
  std::array<uint8_t, 4> application_version{};
  std::array<uint8_t, 4> natnet_version{4, 1, 0, 0};
  uint64_t clock_ticks_per_second = 1'000'000'000;
  uint16_t data_port = kDataPort;
  bool multicast = true;
  std::array<uint8_t, 4> multicast_group{239, 255, 42, 99};
  Version version() const { return {natnet_version[0], natnet_version[1]}; }
};

struct MarkerSetDescription {
  std::string name;
  std::vector<std::string> markers;
};

struct ModelDefinitions {
  std::vector<MarkerSetDescription> marker_sets;
  uint32_t skipped_descriptions = 0;  // rigid bodies, skeletons, ... (not read)
};

using Point = std::array<float, 3>;  // metres, as on the wire

struct MarkerSetData {
  std::string name;
  std::vector<Point> positions;
};

struct LabelledMarker {
  uint32_t id = 0;  // model id << 16 | member id (model 0: an unlabelled point, id = point cloud id)
  Point position{};
  float size = 0.0f;
  int16_t params = 0;
  float residual = 0.0f;
  uint16_t model_id() const { return static_cast<uint16_t>(id >> 16); }
  uint16_t member_id() const { return static_cast<uint16_t>(id & 0xFFFF); }
};

// One frame. Decoding into the same value again reuses its vectors and strings.
struct FrameOfData {
  int32_t frame_number = 0;
  size_t marker_set_count = 0;  // marker_sets[0, count) are this frame's (the rest is kept capacity)
  std::vector<MarkerSetData> marker_sets;
  std::vector<Point> other_markers;
  std::vector<LabelledMarker> labelled_markers;
  uint32_t rigid_bodies = 0, skeletons = 0, assets = 0, force_plates = 0, devices = 0;  // counted, skipped
  uint32_t timecode = 0;
  uint32_t timecode_subframe = 0;
  double timestamp_s = 0.0;
  uint64_t stamp_mid_exposure = 0, stamp_data_received = 0, stamp_transmit = 0;
  uint32_t precise_seconds = 0, precise_fraction = 0;
  int16_t params = 0;
};

// The SMPTE fields of a NatNet timecode.
struct TimecodeFields {
  int hours = 0, minutes = 0, seconds = 0, frames = 0;
};
TimecodeFields split_timecode(uint32_t timecode);
uint32_t join_timecode(const TimecodeFields& fields);

// The frame's time from its cameras' mid-exposure to its transmission, as the server's clock
// (ServerInfo's ticks per second) measured it, in ns; -1 when the stamps do not say (a server
// that leaves them 0, or one that is not monotonic, or more than a second: not a latency).
int64_t capture_latency_ns(const FrameOfData& frame, uint64_t clock_ticks_per_second);

}  // namespace skinstream::natnet
