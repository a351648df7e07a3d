#include "protocol/subscriber/frame_parameters.h"

#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>

#include "protocol/byte_buffer.h"
#include "protocol/byte_reader.h"
#include "protocol/span_writer.h"

namespace skinstream::subscriber {
namespace {

template <size_t N>
bool read_finite(ByteReader& r, std::array<float, N>& out, const char* what) {
  if (!r.get_array(out.data(), N, what)) return false;
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
  SpanWriter w(out);
  w.put<uint32_t>(static_cast<uint32_t>(parts));
  w.put<uint32_t>(static_cast<uint32_t>(members));
  for (const PartParameters& part : parameters.parts) {
    w.put_array<float>(part.quadratic);
    w.put_array<float>(part.rotation);
    w.put_array<float>(part.translation);
    w.put<uint32_t>(part.rbf ? 1u : 0u);
  }
  w.put_array<float>(parameters.weights);  // none for a model of no members
}

void decode_parameter_block(std::span<const unsigned char> block, FrameParameters& out) {
  if (block.size() < 8) throw DecodeError("parameters: block of " + std::to_string(block.size()) + " bytes is truncated");
  ByteReader r(block);  // its size checked against the counts: no read below can fail
  const uint32_t parts = r.get<uint32_t>("part count"), members = r.get<uint32_t>("member count");
  const size_t model_members = out.weights.size() / 3;
  if (parts != out.parts.size() || members != model_members)
    throw DecodeError("parameters: " + std::to_string(parts) + " parts and " + std::to_string(members) + " members, the model has " +
                      std::to_string(out.parts.size()) + " and " + std::to_string(model_members));
  if (block.size() != parameter_block_bytes(static_cast<int>(parts), static_cast<int>(members)))
    throw DecodeError("parameters: block of " + std::to_string(block.size()) + " bytes, the counts say " +
                      std::to_string(parameter_block_bytes(static_cast<int>(parts), static_cast<int>(members))));
  for (uint32_t p = 0; p < parts; ++p) {
    PartParameters& part = out.parts[p];
    if (!read_finite(r, part.quadratic, "part quadratic") ||
        !read_finite(r, part.rotation, "part rotation") ||
        !read_finite(r, part.translation, "part translation"))
      throw DecodeError("parameters: part " + std::to_string(p) + " has a value that is not finite");
    const uint32_t flags = r.get<uint32_t>("part flags");
    if (flags > 1) throw DecodeError("parameters: part " + std::to_string(p) + " has reserved flag bits set (" + std::to_string(flags) + ")");
    part.rbf = flags == 1;
  }
  r.get_array(out.weights.data(), out.weights.size(), "RBF weights");
  for (float w : out.weights)
    if (!std::isfinite(w)) throw DecodeError("parameters: an RBF weight is not finite");
}

}  // namespace skinstream::subscriber
