#pragma once
// The subscriber protocol's Model message (version 2, docs/subscriber-protocol.md): the static
// EvaluationModel a parameter subscriber needs to turn each Frame's parameters into vertices.
// Faces are not in it: they come in MeshInfo, which every subscriber receives first.

#include <span>
#include <vector>

#include "core/deform/evaluation_model.h"
#include "protocol/subscriber/subscriber_stream.h"

namespace skinstream::subscriber {

// The whole message, header included (version 2). Throws std::invalid_argument for a model that
// does not validate or does not fit the format (more than 255 parts or influences on a vertex).
std::vector<unsigned char> encode_model(const EvaluationModel& model);

// The payload of a Model message: every size checked against the payload before anything is
// allocated, then the whole model validated (EvaluationModel::validate); DecodeError otherwise.
// The result has no faces (MeshInfo's go in before it is evaluated).
EvaluationModel decode_model(std::span<const unsigned char> payload);

}  // namespace skinstream::subscriber
