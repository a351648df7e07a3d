// The parameter block of a version 2 Frame, as a parameter subscriber reads it into parameters
// sized for its Model: decode_parameter_block accepts a block or refuses it with a one-line
// DecodeError. The parameters are sized from the block's own counts (within bounds, so that
// mostly the values are fuzzed), or for a model of one part and one member when the counts are
// out of bounds. The decoder never resizes them, and a block it accepts, re-encoded, gives back
// the same bytes.
#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "fuzz/one_line_file_error.h"
#include "protocol/subscriber/frame_parameters.h"

namespace subscriber = skinstream::subscriber;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::span<const unsigned char> block(data, size);
  uint32_t counts[2] = {1, 1};
  if (size >= 8) std::memcpy(counts, data, 8);
  if (counts[0] > 255 || counts[1] > 4096) counts[0] = counts[1] = 1;
  skinstream::FrameParameters parameters;
  parameters.resize(static_cast<int>(counts[0]), static_cast<int>(counts[1]));
  try {
    subscriber::decode_parameter_block(block, parameters);
  } catch (const subscriber::DecodeError& e) {
    skinstream::fuzz::expect_one_printable_line(e.what());
    return 0;
  }
  if (parameters.parts.size() != counts[0] || parameters.weights.size() != 3 * size_t{counts[1]}) std::abort();
  std::vector<unsigned char> again(subscriber::parameter_block_bytes(static_cast<int>(counts[0]), static_cast<int>(counts[1])));
  subscriber::encode_parameter_block(parameters, again);
  if (!std::equal(again.begin(), again.end(), block.begin(), block.end())) std::abort();
  return 0;
}
