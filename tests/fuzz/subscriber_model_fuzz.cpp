// The payload of a version 2 Model message, as a parameter subscriber reads it: decode_model
// accepts a model or refuses it with a one-line DecodeError. A model it accepts is safe to use as
// a renderer does (MeshEvaluator built from it and evaluated in the rest pose, under the
// sanitizers) and, re-encoded, gives back the same payload (its padding aside).
#include <algorithm>
#include <cstdlib>
#include <vector>

#include "core/deform/mesh_evaluator.h"
#include "fuzz/one_line_file_error.h"
#include "protocol/subscriber/subscriber_model.h"

namespace subscriber = skinstream::subscriber;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::span<const unsigned char> payload(data, size);
  skinstream::EvaluationModel model;
  try {
    model = subscriber::decode_model(payload);
  } catch (const subscriber::DecodeError& e) {
    skinstream::fuzz::expect_one_printable_line(e.what());
    return 0;
  }
  skinstream::MeshEvaluator evaluator(model);  // throws (a finding) on a model that does not validate
  std::vector<float> positions(3 * static_cast<size_t>(model.vertex_count())), normals(positions.size());
  if (!evaluator.evaluate(skinstream::rest_parameters(model), positions, normals)) std::abort();

  if (model.part_count() > 255) return 0;  // the encoder's limit, not the format's
  const std::vector<unsigned char> message = subscriber::encode_model(model);
  std::vector<unsigned char> expected(payload.begin(), payload.end());
  // The padding after the influence parts is the decoder's to skip, whatever it holds.
  const size_t v = static_cast<size_t>(model.vertex_count()), influences = static_cast<size_t>(model.influence_count());
  const size_t padding = 16 + 12 * v + 80 * static_cast<size_t>(model.part_count()) + 12 * static_cast<size_t>(model.member_count()) + v + influences;
  std::fill(expected.begin() + static_cast<std::ptrdiff_t>(padding), expected.begin() + static_cast<std::ptrdiff_t>(padding + (4 - (v + influences) % 4) % 4), 0);
  if (!std::equal(message.begin() + subscriber::kHeaderBytes, message.end(), expected.begin(), expected.end())) std::abort();
  return 0;
}
