#pragma once
// The QTM RT commands skinstream sends and serves, parsed from a Command packet's text and
// written back. Command words are case-insensitive, as QTM reads them:
//   Version [1.N]                 set (or ask) the protocol version
//   GetState                      answered with an Event packet
//   GetParameters General 3D ...  answered with XML (protocol/qtm/qtm_parameters.h)
//   StreamFrames AllFrames|Frequency:N|FrequencyDivisor:N [UDP[:address]:port] 3D 3DNoLabels ...
//   StreamFrames Stop
//   QTMVersion, ByteOrder, GetCurrentFrame 3D ...
// Anything else parses as Kind::Other (a server answers it with an Error packet).

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace skinstream::qtm {

struct Command {
  enum class Kind { Version, GetState, GetParameters, StreamFrames, StreamFramesStop, QtmVersion, ByteOrder,
                    GetCurrentFrame, Other };
  enum class Rate { AllFrames, Frequency, FrequencyDivisor };

  Kind kind = Kind::Other;
  std::string word;  // the command word as sent
  int major = 0, minor = -1;  // Version; minor -1 when the version was only asked for
  std::vector<std::string> components;  // GetParameters, StreamFrames, GetCurrentFrame, as given
  Rate rate = Rate::AllFrames;
  uint32_t rate_value = 0;  // Frequency:N or FrequencyDivisor:N
  bool udp = false;
  std::string udp_address;  // empty: the sender's address
  uint16_t udp_port = 0;
};

// A malformed argument of a known command (a bad version, rate or UDP port) is an error; an
// unknown command is not (Kind::Other).
bool parse_command(std::string_view text, Command& out, std::string& out_error);

bool same_word(std::string_view a, std::string_view b);  // ASCII case-insensitive

// "StreamFrames AllFrames 3D 3DNoLabels", "StreamFrames AllFrames UDP:5000 3D", ...
std::string stream_frames_command(const std::vector<std::string>& components, uint16_t udp_port = 0);

}  // namespace skinstream::qtm
