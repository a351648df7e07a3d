// The text of a QTM RT Command packet, as skinstream's replay server reads it (parse_command): any
// text parses or is refused with a one-line reason, and what parses is in range (a version of
// at most 99.99, a non-zero rate for Frequency and FrequencyDivisor, a UDP port when UDP is
// asked for, components when frames are streamed).
#include <cstdlib>
#include <string>
#include <string_view>

#include "fuzz/one_line_file_error.h"
#include "protocol/qtm/qtm_command.h"

namespace qtm = skinstream::qtm;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  qtm::Command command;
  std::string error;
  if (!qtm::parse_command(std::string_view(reinterpret_cast<const char*>(data), size), command, error)) {
    skinstream::fuzz::expect_one_printable_line(error);
    return 0;
  }
  using Kind = qtm::Command::Kind;
  if (command.word.empty()) std::abort();
  if (command.kind == Kind::Version && (command.major > 99 || command.minor > 99)) std::abort();
  if (command.kind == Kind::StreamFrames) {
    if (command.components.empty()) std::abort();
    if (command.rate != qtm::Command::Rate::AllFrames && command.rate_value == 0) std::abort();
    if (command.udp && command.udp_port == 0) std::abort();
  }
  return 0;
}
