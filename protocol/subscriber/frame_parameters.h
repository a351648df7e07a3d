#pragma once
// The parameter block of a version 2 Frame (docs/subscriber-protocol.md): one frame's part
// parameters (core/deform/part_parameters.h) as bytes. Written by the daemon 120 times a second
// and read by renderers as often, so both directions work in buffers sized once.

#include <span>

#include "core/deform/part_parameters.h"
#include "protocol/subscriber/subscriber_stream.h"

namespace skinstream::subscriber {

inline constexpr size_t kPartParameterBytes = 160;

// The block's size for a model of these counts (a multiple of 4).
size_t parameter_block_bytes(int part_count, int member_count);
// Writes the block into `out`, exactly parameter_block_bytes() long; allocates nothing.
void encode_parameter_block(const FrameParameters& parameters, std::span<unsigned char> out);
// Reads a block into `out`, which must already be sized for the model (FrameParameters::resize):
// its counts must match, and every value be finite; DecodeError otherwise. Allocates nothing.
void decode_parameter_block(std::span<const unsigned char> block, FrameParameters& out);

}  // namespace skinstream::subscriber
