/* skinstream's parameter evaluation behind a C ABI, for programs that call C rather than C++
   (Python's ctypes, C#, Rust, Julia): the daemon's own evaluator of eqs. 8 and 9 in
   libskinstream_client. A program that reads the subscriber protocol itself
   (docs/subscriber-protocol.md, the parameter encoding) hands over the Model message's payload
   and MeshInfo's triangles once, then each Frame's parameter block, and gets the vertices the
   daemon's float encoding would have carried for that frame, bit for bit, and its normals.

     char error[256];
     skinstream_evaluator* e = skinstream_evaluator_create(model, model_bytes, faces, face_count, error,
   sizeof error); if (e == NULL) { fprintf(stderr, "%s\n", error); return 1; } float* positions = malloc(12 *
   skinstream_evaluator_vertex_count(e));  // and normals alike if (skinstream_evaluator_evaluate(e, block,
   block_bytes, positions, normals, error, sizeof error) != 0) ... skinstream_evaluator_destroy(e);

   Errors: a function that fails writes one line saying why into `error` (at most error_bytes
   bytes with its terminating NUL; error may be NULL) and returns NULL or non-zero. No C++
   exception leaves these functions. An evaluator is used by one thread at a time; evaluators
   are independent of each other. */
#ifndef SKINSTREAM_EVALUATOR_C_H
#define SKINSTREAM_EVALUATOR_C_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Raised when a function's meaning changes; a caller that loads the library at run time checks
   skinstream_evaluator_abi_version() against the version it was written for. */
#define SKINSTREAM_EVALUATOR_ABI_VERSION 1

typedef struct skinstream_evaluator skinstream_evaluator;

/* SKINSTREAM_EVALUATOR_ABI_VERSION of the library loaded. */
uint32_t skinstream_evaluator_abi_version(void);

/* An evaluator of the model in a Model message's payload (the bytes after its 12-byte header;
   copied, the caller keeps its buffer) with the mesh's triangles from MeshInfo: face_count x 3
   vertex indices, counter-clockwise from outside (for the normals; face_count 0: every normal
   is zero). NULL when the payload breaks the protocol or the model does not validate. */
skinstream_evaluator* skinstream_evaluator_create(const unsigned char* model_payload, size_t model_bytes,
                                                  const uint32_t* faces, size_t face_count, char* error,
                                                  size_t error_bytes);

/* The model's vertex count: the output arrays hold 3 floats for each. */
uint32_t skinstream_evaluator_vertex_count(const skinstream_evaluator* evaluator);

/* Evaluates one Frame's parameter block (docs/subscriber-protocol.md, "Parameters") into
   out_positions (3 floats a vertex, mm, the mesh's vertex order) and, unless it is NULL,
   out_normals (3 floats a vertex, unit). 0 on success; non-zero when the block does not fit the
   model or holds a value that is not finite (the outputs are then left as they were). */
int skinstream_evaluator_evaluate(skinstream_evaluator* evaluator, const unsigned char* parameter_block,
                                  size_t block_bytes, float* out_positions, float* out_normals, char* error,
                                  size_t error_bytes);

/* Frees the evaluator; NULL is ignored. */
void skinstream_evaluator_destroy(skinstream_evaluator* evaluator);

#ifdef __cplusplus
}
#endif

#endif /* SKINSTREAM_EVALUATOR_C_H */
