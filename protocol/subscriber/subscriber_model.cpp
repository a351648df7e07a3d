#include "protocol/subscriber/subscriber_model.h"

#include <stdexcept>
#include <string>

#include "protocol/byte_buffer.h"
#include "protocol/byte_reader.h"

namespace skinstream::subscriber {
namespace {

constexpr size_t kPartBytes = 80;

template <size_t N>
void put_floats(ByteWriter& w, const std::array<float, N>& values) {
  for (float v : values) w.put<float>(v);
}

template <size_t N>
void get_floats(ByteReader& r, std::array<float, N>& values, const char* what) {
  r.get_array(values.data(), N, what);
}

}  // namespace

std::vector<unsigned char> encode_model(const EvaluationModel& model) {
  const std::string problem = model.validate();
  if (!problem.empty()) throw std::invalid_argument("encode_model: " + problem);
  if (model.part_count() > 255) throw std::invalid_argument("encode_model: more than 255 parts");
  const int v = model.vertex_count();
  ByteWriter p;
  p.put<uint32_t>(static_cast<uint32_t>(v));
  p.put<uint32_t>(static_cast<uint32_t>(model.part_count()));
  p.put<uint32_t>(static_cast<uint32_t>(model.member_count()));
  p.put<uint32_t>(static_cast<uint32_t>(model.influence_count()));
  p.put_bytes(model.reference_vertices.data(), model.reference_vertices.size() * sizeof(float));
  for (const EvaluationPart& part : model.parts) {
    put_floats(p, part.rotation);
    put_floats(p, part.translation);
    put_floats(p, part.box_min);
    put_floats(p, part.box_max);
    p.put<float>(part.sigma);
    p.put<uint32_t>(static_cast<uint32_t>(part.member_count));
  }
  p.put_bytes(model.member_reference.data(), model.member_reference.size() * sizeof(float));
  for (int i = 0; i < v; ++i) {
    const int count = model.influence_offsets[i + 1] - model.influence_offsets[i];
    if (count > 255)
      throw std::invalid_argument("encode_model: vertex " + std::to_string(i) +
                                  " has more than 255 influences");
    p.put<uint8_t>(static_cast<uint8_t>(count));
  }
  for (int part : model.influence_parts) p.put<uint8_t>(static_cast<uint8_t>(part));
  for (size_t i = 0; i < padding_to_4(static_cast<size_t>(v) + model.influence_parts.size()); ++i)
    p.put<uint8_t>(0);
  p.put_bytes(model.influence_weights.data(), model.influence_weights.size() * sizeof(float));

  std::vector<unsigned char> message(kHeaderBytes + p.bytes().size());
  write_header(MessageType::Model, kVersion2, p.bytes().size(),
               std::span<unsigned char, kHeaderBytes>(message.data(), kHeaderBytes));
  std::copy(p.bytes().begin(), p.bytes().end(), message.begin() + kHeaderBytes);
  return message;
}

EvaluationModel decode_model(std::span<const unsigned char> payload) {
  ByteReader r(payload);
  EvaluationModel model;
  const uint64_t v = r.get<uint32_t>("vertex count"), parts = r.get<uint32_t>("part count"),
                 members = r.get<uint32_t>("member count"), influences = r.get<uint32_t>("influence count");
  if (!r.ok()) throw DecodeError("Model: " + r.error().message());
  // The sizes the counts imply, against the payload, before anything is allocated: the reads
  // below cannot fail.
  const uint64_t expected = 16 + 12 * v + kPartBytes * parts + 12 * members + v + influences +
                            padding_to_4(v + influences) + 4 * influences;
  if (expected != payload.size())
    throw DecodeError("Model: counts (" + std::to_string(v) + " vertices, " + std::to_string(parts) +
                      " parts, " + std::to_string(members) + " members, " + std::to_string(influences) +
                      " influences) say " + std::to_string(expected) + " bytes, the payload holds " +
                      std::to_string(payload.size()));
  model.reference_vertices.resize(3 * v);
  r.get_array(model.reference_vertices.data(), model.reference_vertices.size(), "reference vertices");
  model.parts.resize(parts);
  for (EvaluationPart& part : model.parts) {
    get_floats(r, part.rotation, "part rotation");
    get_floats(r, part.translation, "part translation");
    get_floats(r, part.box_min, "part box");
    get_floats(r, part.box_max, "part box");
    part.sigma = r.get<float>("part sigma");
    const uint32_t count = r.get<uint32_t>("part member count");
    if (count > members)
      throw DecodeError("Model: a part of " + std::to_string(count) + " members, more than the " +
                        std::to_string(members) + " in all");
    part.member_count = static_cast<int>(count);
  }
  model.member_reference.resize(3 * members);
  r.get_array(model.member_reference.data(), model.member_reference.size(), "member reference");
  model.influence_offsets.assign(v + 1, 0);
  for (uint64_t i = 0; i < v; ++i)
    model.influence_offsets[i + 1] = model.influence_offsets[i] + r.get<uint8_t>("influence count");
  if (static_cast<uint64_t>(model.influence_offsets.back()) != influences)
    throw DecodeError("Model: the vertices count " + std::to_string(model.influence_offsets.back()) +
                      " influences, the header " + std::to_string(influences));
  model.influence_parts.resize(influences);
  for (int& part : model.influence_parts) part = r.get<uint8_t>("influence part");
  r.skip(padding_to_4(v + influences), "influence padding");
  model.influence_weights.resize(influences);
  r.get_array(model.influence_weights.data(), model.influence_weights.size(), "influence weights");
  if (!r.ok()) throw DecodeError("Model: " + r.error().message());
  const std::string problem = model.validate();
  if (!problem.empty()) throw DecodeError("Model: " + problem);
  return model;
}

}  // namespace skinstream::subscriber
