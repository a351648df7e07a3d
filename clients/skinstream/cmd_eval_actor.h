#pragma once
// skinstream eval-actor: how well a subject built for a real actor follows markers it was not
// given. The take is split in two; for each fold, k markers are withheld, a subject is built
// from the first half without them (the template fitted, registered, made deformable), the
// second half is deformed from the other markers, and each withheld marker is attached to the
// deformed surface at the reference frame (the closest surface point plus its offset in that
// triangle's frame) and followed: its distance to where it was measured is the error. Folds
// withhold every marker once. Rows: the full method; the fitted template skinned by its own
// weights through the fitted skeleton (linear blend skinning); rigid parts (each segment by
// Horn's fit of its own markers, or its parent's when it has fewer than three). The edge strain
// of the deformed mesh against the fitted template is measured every frame.
//   skinstream eval-actor --capture C [--mesh BODY.obj] [--withhold 5] [--split 0.5] [--stride 2] [--render DIR] [--json]
#include <cstdint>
#include <cstdio>
#include <string>

#include "clients/skinstream/actor_subject.h"
#include "core/fitting/mesh_frame.h"

namespace skinstream::cli {

struct EvalActorOptions {
  std::string capture_path;
  std::string mesh_path;         // the template's body OBJ, or a scan; empty: the bundled template
  MeshFrameOptions mesh_frame;   // the mesh's unit and axes, when not detected
  std::string marker_sets_dir;   // empty: the bundled definitions
  int withhold = 5;              // markers withheld per fold
  double split = 0.5;            // train on this fraction, test on the rest
  int stride = 2;                // test every n-th frame
  int max_folds = 0;             // 0: every fold (each marker withheld once)
  uint64_t seed = 1;             // of the folds' marker order
  ActorSubjectOptions build;
  std::string render_dir;        // when set: PNGs of the first fold (reference pose, a few test frames)
  bool json = false;
};

// Prints the JSON (and a table) to `out`, progress to stderr; returns the exit code.
int run_eval_actor(const EvalActorOptions& options, std::FILE* out);

}  // namespace skinstream::cli
