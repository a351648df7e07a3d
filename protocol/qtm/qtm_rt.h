#pragma once
// The Qualisys Track Manager real-time protocol (QTM RT, openly documented; versions 1.8 and
// later), as QTM serves it and the Qualisys SDKs read it. Pure bytes: no sockets.
//
// skinstream speaks the little-endian port: QTM's base port + 1, 22223 by default, where every
// packet is little-endian from the first byte. (The base port 22222 starts in protocol 1.0,
// big-endian, and 22224 is the big-endian port: neither is spoken here.)
//
// A packet is `u32 size` (the whole packet, these 8 bytes included), `u32 type`, then the body.
// Command, Error and XML bodies are text, NUL-terminated by QTM (clients may leave the NUL out).
// An Event body is one byte, the event id. A Data body is
//   i64 timestamp (us), u32 frame number, u32 component count,
//   per component: u32 size (its 8-byte header included), u32 type, then
//     3D (1):             u32 marker count, u16 2D drop rate, u16 out-of-sync rate,
//                         float32 x, y, z (mm) per label, in the label order of the 3D
//                         parameters; NaN for a label not measured this frame
//     3D no labels (2):   the same header, then float32 x, y, z and u32 id per marker
//     3D residuals (9):   as 3D with a float32 residual after each marker
//     3D no labels residuals (10): as 3D no labels with a float32 residual before the id
// The labels come from the XML reply to `GetParameters 3D` (protocol/qtm/qtm_parameters.h).

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace skinstream::qtm {

using Bytes = std::span<const unsigned char>;

constexpr uint16_t kBasePort = 22222;
constexpr uint16_t kLittleEndianPort = 22223;  // the port skinstream listens on and connects to
constexpr size_t kHeaderBytes = 8;
constexpr uint32_t kMaxPacketBytes = 16u << 20;  // larger is refused: no real frame comes near

// The protocol versions this side accepts (`Version 1.8` ... `Version 1.28`): from 1.8 on the
// 3D components carry float32 positions.
constexpr int kMinMinorVersion = 8;
constexpr int kMaxMinorVersion = 28;
constexpr int kSpokenMinorVersion = 19;  // what skinstream's client asks for

constexpr const char* kWelcome = "QTM RT Interface connected";

enum class PacketType : uint32_t {
  Error = 0,
  Command = 1,
  Xml = 2,
  Data = 3,
  NoMoreData = 4,
  C3dFile = 5,
  Event = 6,
  Discover = 7,
  QtmFile = 8,
};
const char* packet_type_name(uint32_t type);  // "Data", or "unknown"

namespace component {
constexpr uint32_t k3d = 1;
constexpr uint32_t k3dNoLabels = 2;
constexpr uint32_t k3dResiduals = 9;
constexpr uint32_t k3dNoLabelsResiduals = 10;
}  // namespace component

// Events (Event packets, and the answer to GetState).
enum class Event : uint8_t {
  Connected = 1,
  ConnectionClosed = 2,
  CaptureStarted = 3,
  CaptureStopped = 4,
  CalibrationStarted = 6,
  CalibrationStopped = 7,
  RtFromFileStarted = 8,
  RtFromFileStopped = 9,
  WaitingForTrigger = 10,
  CameraSettingsChanged = 11,
  QtmShuttingDown = 12,
  CaptureSaved = 13,
};

struct UnlabelledMarker {
  std::array<float, 3> position{};  // mm
  uint32_t id = 0;                  // QTM's trajectory id
};

// A Data packet's 3D content. Decoding into the same value again reuses its vectors.
struct DataFrame {
  int64_t timestamp_us = 0;
  uint32_t frame_number = 0;
  bool has_labelled = false;    // a 3D (or 3D residuals) component was present
  bool has_unlabelled = false;  // a 3D no labels (or its residuals) component was present
  uint16_t drop_rate_2d = 0;
  uint16_t out_of_sync_rate_2d = 0;
  std::vector<std::array<float, 3>> labelled;  // mm, NaN = not measured; in label order
  std::vector<UnlabelledMarker> unlabelled;
  uint32_t skipped_components = 0;  // components of other types (6D, analog, ...) left unread
};

}  // namespace skinstream::qtm
