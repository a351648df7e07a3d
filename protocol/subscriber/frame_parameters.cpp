#include "protocol/subscriber/frame_parameters.h"

#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>

#include "protocol/byte_buffer.h"

namespace skinstream::subscriber {
namespace {

// Values are copied as they are: the protocol's byte order is the host's (little-endian).
template <size_t N>
bool read_finite(const unsigned char*& at, std::array<float, N>& out) {
  std::memcpy(out.data(), at, N * sizeof(float));
  at += N * sizeof(float);
  for (float v : out)
    if (!std::isfinite(v)) return false;
  return true;
}

}  // namespace

size_t parameter_block_bytes(int part_count, int member_count) {
  return 8 + kPartParameterBytes * static_cast<size_t>(part_count) + 12 * static_cast<size_t>(member_count);
}

void encode_parameter_block(const FrameParameters& parameters, std::span<unsigned char> out) {
  const int parts = static_cast<int>(parameters.parts.size()), members = static_cast<int>(parameters.weights.size() / 3);
  if (out.size() != parameter_block_bytes(parts, members) || parameters.weights.size() % 3 != 0)
    throw std::invalid_argument("encode_parameter_block: the buffer does not fit the parameters");
  unsigned char* at = out.data();
  put_at<uint32_t>(at, static_cast<uint32_t>(parts));
  put_at<uint32_t>(at, static_cast<uint32_t>(members));
  for (const PartParameters& part : parameters.parts) {
    std::memcpy(at, part.quadratic.data(), sizeof(part.quadratic));
    at += sizeof(part.quadratic);
    std::memcpy(at, part.rotation.data(), sizeof(part.rotation));
    at += sizeof(part.rotation);
    std::memcpy(at, part.translation.data(), sizeof(part.translation));
    at += sizeof(part.translation);
    put_at<uint32_t>(at, part.rbf ? 1u : 0u);
  }
  // A model of no members has no weights (and an empty vector's data() may be null).
  if (!parameters.weights.empty()) std::memcpy(at, parameters.weights.data(), parameters.weights.size() * sizeof(float));
}

void decode_parameter_block(std::span<const unsigned char> block, FrameParameters& out) {
  if (block.size() < 8) throw DecodeError("parameters: block of " + std::to_string(block.size()) + " bytes is truncated");
  const unsigned char* at = block.data();
  const uint32_t parts = get_at<uint32_t>(at), members = get_at<uint32_t>(at);
  const size_t model_members = out.weights.size() / 3;
  if (parts != out.parts.size() || members != model_members)
    throw DecodeError("parameters: " + std::to_string(parts) + " parts and " + std::to_string(members) + " members, the model has " +
                      std::to_string(out.parts.size()) + " and " + std::to_string(model_members));
  if (block.size() != parameter_block_bytes(static_cast<int>(parts), static_cast<int>(members)))
    throw DecodeError("parameters: block of " + std::to_string(block.size()) + " bytes, the counts say " +
                      std::to_string(parameter_block_bytes(static_cast<int>(parts), static_cast<int>(members))));
  for (uint32_t p = 0; p < parts; ++p) {
    PartParameters& part = out.parts[p];
    if (!read_finite(at, part.quadratic) || !read_finite(at, part.rotation) || !read_finite(at, part.translation))
      throw DecodeError("parameters: part " + std::to_string(p) + " has a value that is not finite");
    const uint32_t flags = get_at<uint32_t>(at);
    if (flags > 1) throw DecodeError("parameters: part " + std::to_string(p) + " has reserved flag bits set (" + std::to_string(flags) + ")");
    part.rbf = flags == 1;
  }
  if (!out.weights.empty()) std::memcpy(out.weights.data(), at, out.weights.size() * sizeof(float));
  for (float w : out.weights)
    if (!std::isfinite(w)) throw DecodeError("parameters: an RBF weight is not finite");
}

}  // namespace skinstream::subscriber
