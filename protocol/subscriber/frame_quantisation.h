#pragma once
// The quantised encoding of a Frame message's positions and normals (docs/subscriber-protocol.md):
// positions as u16 steps of a per-axis box, unit normals as i16 of n * 32767, both rounded
// half away from zero. Run on the daemon's 120 Hz thread whenever a subscriber (the browser
// preview by default) asks for it, so it is written for vector lanes; every value equals the
// one std::round / std::lround give (tests/protocol/subscriber/frame_quantisation_test.cpp checks).
#include <cstdint>
#include <span>

namespace skinstream::subscriber {

struct QuantisationBox {
  float lo[3] = {0, 0, 0};    // the least finite value per axis, 0 without one
  float step[3] = {0, 0, 0};  // (greatest - least) / 65535, 0 on a flat axis or without one
};

// positions: 3 floats a vertex.
QuantisationBox quantisation_box(std::span<const float> positions);

// Each coordinate as round((x - lo) / step) clamped to [0, 65535], 0 when not finite or its
// axis is flat;
// 2 * positions.size() little-endian bytes (u16) to `out`.
void quantise_positions(std::span<const float> positions, const QuantisationBox& box, unsigned char* out);

// Each component clamped to [-1, 1] (0 when not finite) as round(n * 32767);
// 2 * normals.size() little-endian bytes (i16) to `out`.
void quantise_normals(std::span<const float> normals, unsigned char* out);

}  // namespace skinstream::subscriber
