// QTM RT bytes as skinstream's QTM client and the replay server meet them: the framer cuts the
// stream, fed in pieces of 1 to 64 bytes (from the input's length, so seeds stay whole packets),
// and every packet goes through decode_packet, a Command's text on through parse_command and an
// XML packet's through parse_parameters_xml; the whole input is also decoded as one packet.
// Whatever the bytes, a refusal is one printable line, the framer and the whole-packet decoder
// agree on what they accept, and a decoded Data packet holds what its components said.
#include <algorithm>
#include <cstdlib>
#include <string>

#include "fuzz/one_line_file_error.h"
#include "protocol/qtm/qtm_command.h"
#include "protocol/qtm/qtm_packet_framer.h"
#include "protocol/qtm/qtm_packet_reader.h"
#include "protocol/qtm/qtm_parameters.h"

namespace qtm = skinstream::qtm;
using skinstream::fuzz::expect_one_printable_line;

namespace {

void expect_refusal_is_one_line(bool ok, const std::string& error) {
  if (!ok) expect_one_printable_line(error);
}

// Decodes one packet as the client and the server would; false when decode_packet refused it.
bool decode(qtm::Bytes bytes) {
  qtm::Packet packet;
  std::string error;
  const bool ok = qtm::decode_packet(bytes, packet, error);
  expect_refusal_is_one_line(ok, error);
  if (!ok) return false;
  if (packet.type == static_cast<uint32_t>(qtm::PacketType::Command)) {
    qtm::Command command;
    expect_refusal_is_one_line(qtm::parse_command(packet.text, command, error), error);
  } else if (packet.type == static_cast<uint32_t>(qtm::PacketType::Xml)) {
    qtm::Parameters parameters;
    expect_refusal_is_one_line(qtm::parse_parameters_xml(packet.text, parameters, error), error);
  } else if (packet.type == static_cast<uint32_t>(qtm::PacketType::Data)) {
    const qtm::DataFrame& d = packet.data;
    if ((!d.has_labelled && !d.labelled.empty()) || (!d.has_unlabelled && !d.unlabelled.empty())) std::abort();
    // Every marker took at least 12 bytes of the packet.
    if ((d.labelled.size() + d.unlabelled.size()) * 12 > bytes.size()) std::abort();
  }
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const size_t piece = 1 + size % 64;
  const qtm::Bytes stream(data, size);
  const bool whole_ok = decode(stream);

  qtm::PacketFramer framer(1u << 20);
  qtm::Bytes packet;
  size_t fed = 0, packets = 0;
  bool refused = false, first_ok = false;
  while (fed < stream.size() && !refused) {
    const size_t n = std::min(piece, stream.size() - fed);
    framer.feed(stream.subspan(fed, n));
    fed += n;
    for (;;) {
      const qtm::PacketFramer::Status status = framer.next(packet);
      if (status == qtm::PacketFramer::Status::NeedMore) break;
      if (status == qtm::PacketFramer::Status::Error) {
        expect_one_printable_line(framer.error());
        refused = true;
        break;
      }
      const bool ok = decode(packet);
      if (packets++ == 0) first_ok = ok;
    }
  }
  // One whole packet is what both take: the framer cuts exactly it, and decodes it the same.
  if (whole_ok && (refused || packets != 1 || framer.buffered() != 0 || !first_ok)) std::abort();
  return 0;
}
