// The C ABI of include/skinstream/evaluator_c.h over the daemon's MeshEvaluator: every C++
// exception is caught here and becomes the caller's one-line error.
#include "skinstream/evaluator_c.h"

#include <algorithm>
#include <cstring>
#include <exception>
#include <limits>
#include <new>
#include <span>
#include <string>

#include "core/deform/mesh_evaluator.h"
#include "protocol/subscriber/frame_parameters.h"
#include "protocol/subscriber/subscriber_model.h"
#include "protocol/subscriber/subscriber_stream.h"

struct skinstream_evaluator {
  skinstream::MeshEvaluator evaluator;
  skinstream::FrameParameters parameters;  // sized for the model once: a frame allocates nothing

  explicit skinstream_evaluator(const skinstream::EvaluationModel& model) : evaluator(model) {
    parameters.resize(model.part_count(), model.member_count());
  }
};

namespace {

void write_error(char* error, size_t error_bytes, const std::string& what) {
  if (error == nullptr || error_bytes == 0) return;
  const size_t n = std::min(what.size(), error_bytes - 1);
  std::memcpy(error, what.data(), n);
  error[n] = '\0';
}

// Runs `work`, turning what it throws into the error line; false when it threw. The protocol's
// decode errors already say what they are about ("Model: ...", "parameters: ...").
template <typename Work>
bool guarded(char* error, size_t error_bytes, const char* what, Work&& work) {
  try {
    work();
    return true;
  } catch (const skinstream::subscriber::DecodeError& e) {
    write_error(error, error_bytes, e.what());
  } catch (const std::bad_alloc&) {
    write_error(error, error_bytes, std::string(what) + ": out of memory");
  } catch (const std::exception& e) {
    write_error(error, error_bytes, std::string(what) + ": " + e.what());
  } catch (...) {
    write_error(error, error_bytes, std::string(what) + ": unknown error");
  }
  return false;
}

}  // namespace

extern "C" {

uint32_t skinstream_evaluator_abi_version(void) { return SKINSTREAM_EVALUATOR_ABI_VERSION; }

skinstream_evaluator* skinstream_evaluator_create(const unsigned char* model_payload, size_t model_bytes,
                                                  const uint32_t* faces, size_t face_count, char* error,
                                                  size_t error_bytes) {
  if (model_payload == nullptr && model_bytes > 0) {
    write_error(error, error_bytes, "Model: no payload");
    return nullptr;
  }
  if (faces == nullptr && face_count > 0) {
    write_error(error, error_bytes, "faces: none given for a count of " + std::to_string(face_count));
    return nullptr;
  }
  if (face_count > static_cast<size_t>(std::numeric_limits<int>::max()) / 3) {
    write_error(error, error_bytes, "faces: " + std::to_string(face_count) + " is more than a mesh holds");
    return nullptr;
  }
  skinstream_evaluator* created = nullptr;
  guarded(error, error_bytes, "Model", [&] {
    skinstream::EvaluationModel model = skinstream::subscriber::decode_model({model_payload, model_bytes});
    model.faces.resize(face_count);
    for (size_t f = 0; f < face_count; ++f)
      for (int c = 0; c < 3; ++c) {
        const uint32_t index = faces[3 * f + c];
        // Indices past int's range become -1: validate() names the face as out of range.
        model.faces[f][c] =
            index > static_cast<uint32_t>(std::numeric_limits<int>::max()) ? -1 : static_cast<int>(index);
      }
    created = new skinstream_evaluator(model);  // MeshEvaluator validates the model, faces included
  });
  return created;
}

uint32_t skinstream_evaluator_vertex_count(const skinstream_evaluator* evaluator) {
  return evaluator == nullptr ? 0 : static_cast<uint32_t>(evaluator->evaluator.vertex_count());
}

int skinstream_evaluator_evaluate(skinstream_evaluator* evaluator, const unsigned char* parameter_block,
                                  size_t block_bytes, float* out_positions, float* out_normals, char* error,
                                  size_t error_bytes) {
  if (evaluator == nullptr || out_positions == nullptr) {
    write_error(
        error, error_bytes,
        evaluator == nullptr ? "parameters: no evaluator" : "parameters: no output for the positions");
    return 1;
  }
  if (parameter_block == nullptr && block_bytes > 0) {
    write_error(error, error_bytes, "parameters: no block");
    return 1;
  }
  bool fits = false;
  const bool ran = guarded(error, error_bytes, "parameters", [&] {
    skinstream::subscriber::decode_parameter_block({parameter_block, block_bytes}, evaluator->parameters);
    const size_t floats = 3 * static_cast<size_t>(evaluator->evaluator.vertex_count());
    fits = evaluator->evaluator.evaluate(
        evaluator->parameters, {out_positions, floats},
        out_normals == nullptr ? std::span<float>() : std::span<float>(out_normals, floats));
  });
  if (!ran) return 1;
  if (!fits) {
    write_error(error, error_bytes, "parameters: the block does not fit the model");
    return 1;
  }
  return 0;
}

void skinstream_evaluator_destroy(skinstream_evaluator* evaluator) { delete evaluator; }

}  // extern "C"
